"""What a model needs to know about the data it will be trained on: the scene."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SCALE_FLOOR = 1e-6  # a component whose std is at most this is centred, not rescaled


def _floats(x) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(x, float).ravel())


@dataclass(frozen=True)
class Standardisation:
    """Affine maps around a scene's networks, fixed from the training data (the paper's MuJoCo
    models, ngruver/decon-hnn ``mujoco.py``): each network input x -> (x - loc) / scale for the
    non-angular q, the velocities (or momenta) and the controls u; a network whose output is a
    rate of the state gives loc + scale * y, with the statistics of the finite-difference rates
    (dq/dt, dv/dt) ~ (Delta q, Delta v) / dt of consecutive training states: the NODE's field
    and the NODE+SO's acceleration; the other models standardise their inputs only (the
    reference's MixtureHNN too). Angles keep their (cos q, sin q) embedding. Not trained: the
    fields are constants of the model."""

    q_loc: tuple[float, ...]
    q_scale: tuple[float, ...]
    v_loc: tuple[float, ...]
    v_scale: tuple[float, ...]
    u_loc: tuple[float, ...]
    u_scale: tuple[float, ...]
    rate_loc: tuple[float, ...]
    rate_scale: tuple[float, ...]

    def __post_init__(self):
        for name in self.__dataclass_fields__:
            object.__setattr__(self, name, _floats(getattr(self, name)))
        d = len(self.q_loc)
        sizes = {"q_scale": d, "v_loc": d, "v_scale": d, "rate_loc": 2 * d, "rate_scale": 2 * d}
        sizes["u_scale"] = len(self.u_loc)
        for name, n in sizes.items():
            if len(getattr(self, name)) != n:
                raise ValueError(f"Standardisation.{name} must have {n} entries")
        scales = self.q_scale + self.v_scale + self.u_scale + self.rate_scale
        if not all(np.isfinite(scales)) or min(scales, default=1.0) <= 0:
            raise ValueError("Standardisation scales must be finite and > 0")

    @classmethod
    def from_windows(cls, z, u, dt: float) -> Standardisation:
        """From training windows z (N, C, 2d) and their controls u (N, C, nu) at step ``dt``:
        the mean and std over every window state (and control), and over the finite-difference
        rates of consecutive states; a std at most :data:`SCALE_FLOOR` becomes 1."""
        z, u = np.asarray(z, float), np.asarray(u, float)
        d = z.shape[-1] // 2
        rates = (np.diff(z, axis=1) / dt).reshape(-1, 2 * d)
        states, controls = z.reshape(-1, 2 * d), u.reshape(-1, u.shape[-1])

        def scale(x):
            s = x.std(0)
            return np.where(s > SCALE_FLOOR, s, 1.0)

        return cls(
            q_loc=states[:, :d].mean(0),
            q_scale=scale(states[:, :d]),
            v_loc=states[:, d:].mean(0),
            v_scale=scale(states[:, d:]),
            u_loc=controls.mean(0),
            u_scale=scale(controls),
            rate_loc=rates.mean(0),
            rate_scale=scale(rates),
        )

    def rate(self, y, dtype, part: slice = slice(None)):
        """A network's output y as a rate of the state (``part``: of dz/dt's entries)."""
        import jax.numpy as jnp

        loc = jnp.asarray(self.rate_loc[part], dtype)
        return loc + jnp.asarray(self.rate_scale[part], dtype) * y


@dataclass(frozen=True)
class Scene:
    """A system as the models see it.

    ``dof`` configuration coordinates q; the state is z = (q, qdot), or z = (q, p) when
    ``canonical``. ``angular[i]`` says q_i is an angle (fed to networks as (cos q_i, sin q_i)).
    ``n_args`` per-trajectory parameters (e.g. g) are fed to every network as extra inputs.
    ``n_controls`` control inputs u (a controlled scene: Gym MuJoCo tasks, u held constant
    over each interval of a rollout) travel with the args: a model's ``args`` is then the
    concatenation (static args, u) of length n_args + n_controls, built per interval by
    ``models.rollout``. Only the parts of a model that may depend on u read it (see
    ``Features``); mass matrices, potentials, Hamiltonians and Lagrangians never do.
    ``damped`` turns on the dissipation part of the structured models by default.
    ``standardisation`` (a :class:`Standardisation`, or None) standardises every network's
    inputs and the rate networks' outputs with the training data's statistics.
    """

    dof: int
    angular: tuple[bool, ...]
    n_args: int = 0
    damped: bool = False
    canonical: bool = False
    n_controls: int = 0
    standardisation: Standardisation | None = None

    def __post_init__(self):
        if isinstance(self.dof, bool) or not isinstance(self.dof, int) or self.dof < 1:
            raise ValueError(f"Scene.dof must be an int >= 1, got {self.dof!r}")
        angular = tuple(bool(a) for a in self.angular)
        if len(angular) != self.dof:
            raise ValueError(f"Scene.angular must have dof={self.dof} entries, got {len(angular)}")
        object.__setattr__(self, "angular", angular)
        if isinstance(self.n_args, bool) or not isinstance(self.n_args, int) or self.n_args < 0:
            raise ValueError(f"Scene.n_args must be an int >= 0, got {self.n_args!r}")
        n_u = self.n_controls
        if isinstance(n_u, bool) or not isinstance(n_u, int) or n_u < 0:
            raise ValueError(f"Scene.n_controls must be an int >= 0, got {n_u!r}")
        st = self.standardisation
        if st is not None:
            if not isinstance(st, Standardisation):
                raise ValueError("Scene.standardisation must be a Standardisation or None")
            if len(st.q_loc) != self.dof or len(st.u_loc) != n_u:
                raise ValueError(
                    f"Scene.standardisation must describe dof={self.dof} coordinates and "
                    f"n_controls={n_u} controls; got {len(st.q_loc)} and {len(st.u_loc)}"
                )
        object.__setattr__(self, "damped", bool(self.damped))
        object.__setattr__(self, "canonical", bool(self.canonical))

    @property
    def state_size(self) -> int:
        return 2 * self.dof

    @property
    def args_size(self) -> int:
        """Length of a model's ``args``: n_args static parameters, then n_controls controls."""
        return self.n_args + self.n_controls
