"""Whether a learned embedding of a pendulum's frames has the structure of the true one: the
VIN seed's evidence (its blog's figure of "embedded representations": the VIN-SO(2)'s is
"consistent with the ground truth"; the baselines' "fail to capture the global structure" or
are "discontinuous with respect to the time dimension").

The truth of a frame is the bob's position on the unit circle, g = (sin theta, -cos theta)
(the ground-truth panel of the seed's figure); the learned embedding e is the encoder's
position of the same frame (so2: (cos q, sin q); r2: q). Over the frames of some test
trajectories, each kept whole and in time order, with ranks r_g(i, j) and r_e(i, j) (j is the
r-th nearest frame to i in the true / learned embedding, 1 the nearest):

* **trustworthiness** (Venna & Kaski 2001) at k neighbours, N frames: the frames among the k
  nearest of i in the learned embedding that are not among its k nearest on the true circle,
  charged by how far they are there::

      T = 1 - 2 / (N k (2N - 3k - 1)) sum_i sum_{j in U_k(i)} (r_g(i, j) - k)

  1 for an embedding whose neighbours are true neighbours, about 0.5 for a random one; a fold
  (two arcs of the circle on one curve) or a wrap of degree 2 lowers it. "Lies on a closed
  curve like the truth's".
* **jumps**: the share of consecutive frames (t, t + 1) of a trajectory whose learned step is
  a jump, r_e(t, t + 1) > kappa max(k, r_g(t, t + 1)): the next frame lands farther down the
  learned neighbour ranks than ``kappa`` times where it is on the circle (or than k). 0 for an
  embedding that follows time continuously; a cut of the curve costs the steps that cross it.
  "Ordered along the curve as in time".
* **defect** = max(1 - T, jumps): 0 for the truth and any embedding continuous and one-to-one
  on it (rotated, reflected, stretched); the synthetic cases of tests/test_vin_blog.py give
  about 0.01-0.03 for an embedding with small noise, 0.06 for a curve cut where the swings
  cross it, 0.2-0.3 for a fold, 0.45 for a double wrap and 0.65 for a random order.

k = :data:`K`, kappa = :data:`KAPPA`; frames with a non-finite embedding make the defect 1.
"""

from __future__ import annotations

import numpy as np

K = 10
KAPPA = 4.0
MAX_FRAMES = 800  # whole trajectories up to this many frames (the ranks are N x N)


def ranks(x: np.ndarray) -> np.ndarray:
    """(N, N) neighbour ranks: ``r[i, j]`` = 1 + the number of points nearer to i than j
    (Euclidean; ties broken by index), ``r[i, i]`` = N."""
    x = np.asarray(x, dtype=np.float64).reshape(len(x), -1)
    d = np.sum((x[:, None, :] - x[None, :, :]) ** 2, axis=-1)
    np.fill_diagonal(d, np.inf)
    order = np.argsort(d, axis=1, kind="stable")
    n = len(x)
    r = np.empty_like(order)
    r[np.arange(n)[:, None], order] = np.arange(1, n + 1)[None, :]
    return r


def trustworthiness(r_learned: np.ndarray, r_true: np.ndarray, k: int = K) -> float:
    """Venna and Kaski's trustworthiness of the learned ranks against the true ones."""
    n = len(r_true)
    k = min(k, max(1, (n - 1) // 3))
    intruders = (r_learned <= k) & (r_true > k)
    norm = 2.0 / (n * k * (2 * n - 3 * k - 1))
    return float(1.0 - norm * np.sum(np.where(intruders, r_true - k, 0)))


def structure(learned, angles, k: int = K, kappa: float = KAPPA) -> dict:
    """``{"trust", "jumps", "defect"}`` of a learned embedding (n_traj, T, D) of the frames at
    the true angles (n_traj, T) (the module docstring); whole trajectories up to
    :data:`MAX_FRAMES` frames."""
    e = np.asarray(learned, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    if e.ndim == 2:
        e = e[..., None]
    if e.shape[:2] != a.shape:
        raise ValueError(f"learned (n, T, D) and angles (n, T) differ: {e.shape}, {a.shape}")
    n_keep = max(1, min(len(a), MAX_FRAMES // max(1, a.shape[1])))
    e, a = e[:n_keep], a[:n_keep]
    bad = {"trust": float("nan"), "jumps": float("nan"), "defect": 1.0}
    if not np.all(np.isfinite(e)) or a.size < 3 * k + 2:
        return bad
    n_traj, t = a.shape
    g = np.stack([np.sin(a), -np.cos(a)], axis=-1).reshape(n_traj * t, 2)
    r_e, r_g = ranks(e.reshape(n_traj * t, -1)), ranks(g)
    trust = trustworthiness(r_e, r_g, k)
    i = (np.arange(n_traj)[:, None] * t + np.arange(t - 1)[None, :]).ravel()
    jumps = float(np.mean(r_e[i, i + 1] > kappa * np.maximum(k, r_g[i, i + 1])))
    return {"trust": trust, "jumps": jumps, "defect": max(1.0 - trust, jumps)}
