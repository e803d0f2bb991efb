"""Rendering a pendulum to small grey images, and reading the angle back off a frame.

A frame is the pendulum seen side-on: the pivot at the image centre, y up, each link drawn as
a soft capsule (a segment of half-width ``ROD_HALF_WIDTH`` pixels whose edge falls off as a
logistic of the distance, ``EDGE`` pixels wide). The intensity of pixel c is

    I(c) = max over links of sigmoid((w - d(c, segment)) / s),

a smooth function of the angles, so images have gradients with respect to the state (the
HNN seed's frames come from OpenAI Gym's Pendulum-v0 renderer: a bar from the pivot, cropped,
desaturated and downsampled to 28 x 28; ours draws the same picture directly at 28 x 28).
``read_angle`` inverts it: the intensity-weighted centroid of a single-link frame lies on the
rod, so its direction from the pivot is the angle (up to pixelisation).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ._base import AbstractSystem
from ._chain import ChainPendulum
from ._pendulum import Pendulum

ROD_HALF_WIDTH = 1.5  # pixels
EDGE = 0.5  # pixels: the width of the logistic edge (anti-aliasing)
MARGIN = 2.0  # pixels between the longest reach and the image border
RENDERABLE = ("pendulum", "chain_pendulum")


def reach(system: AbstractSystem) -> float:
    """The longest distance of a bob from the pivot (m): the sum of the link lengths."""
    if isinstance(system, Pendulum):
        return float(system.length)
    if isinstance(system, ChainPendulum):
        return float(np.sum(np.asarray(system.lengths)))
    raise ValueError(
        f"cannot render system {getattr(system, 'name', system)!r}; allowed: "
        f"{', '.join(RENDERABLE)}"
    )


def _pixel_centres(size: int):
    """Pixel centres in pixel units relative to the image centre: x right, y up, (size, size)."""
    c = jnp.arange(size) + 0.5 - size / 2
    return c[None, :], -c[:, None]  # x varies along columns, y decreases down the rows


def render_points(points, size: int = 28, scale: float = 1.0):
    """One frame of the chain pivot -> points[0] -> points[1] ...: ``points`` (n, 2) in metres,
    ``scale`` pixels per metre. Returns (size, size) intensities in [0, 1]."""
    x, y = _pixel_centres(size)
    pts = jnp.concatenate([jnp.zeros((1, 2), points.dtype), points * scale], axis=0)

    def link(a, b):
        ab = b - a
        denom = jnp.maximum(jnp.dot(ab, ab), 1e-12)
        u = jnp.clip(((x - a[0]) * ab[0] + (y - a[1]) * ab[1]) / denom, 0.0, 1.0)
        d = jnp.sqrt((x - a[0] - u * ab[0]) ** 2 + (y - a[1] - u * ab[1]) ** 2 + 1e-12)
        return jax.nn.sigmoid((ROD_HALF_WIDTH - d) / EDGE)

    images = jax.vmap(link)(pts[:-1], pts[1:])
    return jnp.max(images, axis=0)


def render(system: AbstractSystem, zs, size: int = 28):
    """Frames of states ``zs`` (..., 2 dof) of a pendulum: (..., size, size), float64.

    The longest reach of the system fills the image less :data:`MARGIN` pixels."""
    if isinstance(size, bool) or not isinstance(size, int) or size < 8:
        raise ValueError(f"size must be an int >= 8 (pixels); got {size!r}")
    scale = (size / 2 - MARGIN) / reach(system)
    zs = jnp.asarray(zs, dtype=jnp.float64)
    flat = zs.reshape(-1, zs.shape[-1])
    frames = jax.vmap(lambda z: render_points(system.positions(z), size, scale))(flat)
    return frames.reshape(*zs.shape[:-1], size, size)


def read_angle(frames):
    """The angle from the downward vertical of a single pendulum in ``frames`` (..., S, S): the
    direction from the pivot of the intensity-weighted centroid (negative intensities, e.g. of
    a decoder's output, count as 0). NaN for an empty frame."""
    frames = jnp.asarray(frames)
    size = frames.shape[-1]
    x, y = _pixel_centres(size)
    w = jnp.clip(frames, 0.0, None)
    total = jnp.sum(w, axis=(-2, -1))
    cx = jnp.sum(w * x, axis=(-2, -1)) / total
    cy = jnp.sum(w * y, axis=(-2, -1)) / total
    return jnp.where(total > 0, jnp.arctan2(cx, -cy), jnp.nan)


def read_state(observations, dt: float):
    """(q, qdot) of observations (..., 2, S, S), two frames dt apart: q the angle of the first
    frame, qdot the wrapped angle difference over dt (a forward difference)."""
    a = read_angle(observations)
    dq = jnp.angle(jnp.exp(1j * (a[..., 1] - a[..., 0])))
    return jnp.stack([a[..., 0], dq / dt], axis=-1)
