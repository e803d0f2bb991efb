"""What a model needs to know about the data it will be trained on: the scene."""

from __future__ import annotations

from dataclasses import dataclass


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
    """

    dof: int
    angular: tuple[bool, ...]
    n_args: int = 0
    damped: bool = False
    canonical: bool = False
    n_controls: int = 0

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
        object.__setattr__(self, "damped", bool(self.damped))
        object.__setattr__(self, "canonical", bool(self.canonical))

    @property
    def state_size(self) -> int:
        return 2 * self.dof

    @property
    def args_size(self) -> int:
        """Length of a model's ``args``: n_args static parameters, then n_controls controls."""
        return self.n_args + self.n_controls
