"""Rigid bodies in ZXZ Euler angles: the gyroscope (a heavy top on a fixed pivot) and the rotor
(a free body), the Deconstructing paper's App. D.2 systems from Finzi et al. (2020).

Their inertia comes from the predecessor's meshes (``gyro.obj``, ``rotor.obj``); the numbers
below and how they were computed: docs/studies/rigid_bodies.md.
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._base import AbstractSystem
from ._params import check_positive, check_real

G = 9.81
MASS = 0.1  # both bodies (the reference's default)
# Second moments diag E[(x - com)(x - com)^T] of the solid meshes (signed tetrahedra, uniform
# density; vertices rolled (x, y, z) -> (z, x, y) as the reference's reader does), from
# mfinzi/constrained-hamiltonian-neural-networks gyro.obj and rotor.obj. The gyroscope's x and y
# agree to 8 digits (an axisymmetric mesh) and are taken equal; its mesh is shifted so that its
# bottom is at z = 0, the pivot, which puts the centre of mass 0.2217 above it on the axis.
GYRO_SECOND_MOMENTS = (2.4137838e-3, 2.4137838e-3, 3.6941541e-4)
GYRO_COM = (0.0, 0.0, 0.22172854)
GYRO_MOMENT_SCALE = 100.0  # the reference's ``moments = 100 * diag(covar)``
# The rotor's covariance has an off-diagonal yz entry 4.1e-4 that the reference drops (it takes
# the mesh axes as principal axes); so do we.
ROTOR_SECOND_MOMENTS = (2.9851343e-3, 9.9063365e-2, 2.1108513e-2)


def _inertia(mass, second_moments, scale=1.0):
    """Principal moments about the centre of mass, I_j = m (sum_i s_i - s_j)."""
    s = np.asarray(second_moments) * scale
    return tuple(float(mass * (s.sum() - sj)) for sj in s)


GYRO_INERTIA = _inertia(MASS, GYRO_SECOND_MOMENTS, GYRO_MOMENT_SCALE)
ROTOR_INERTIA = _inertia(MASS, ROTOR_SECOND_MOMENTS)
# ZXZ Euler angles are singular at sin(beta) = 0; initial states closer than this are refused.
POLE = 1e-3


def rotation_matrix(angles):
    """R = Rz(alpha) Rx(beta) Rz(gamma): intrinsic ZXZ (scipy's ``from_euler("ZXZ", ...)``);
    its columns are the body axes in space."""
    a, b, c = angles[0], angles[1], angles[2]

    def rz(t):
        ct, st = jnp.cos(t), jnp.sin(t)
        return jnp.array([[ct, -st, 0.0], [st, ct, 0.0], [0.0, 0.0, 1.0]])

    cb, sb = jnp.cos(b), jnp.sin(b)
    rx = jnp.array([[1.0, 0.0, 0.0], [0.0, cb, -sb], [0.0, sb, cb]])
    return rz(a) @ rx @ rz(c)


def body_angular_velocity(angles, rates):
    """omega_body with R^T dR/dt = hat(omega_body), for ZXZ angles (alpha, beta, gamma):
    (a' sin b sin c + b' cos c, a' sin b cos c - b' sin c, a' cos b + c')."""
    _, b, c = angles[0], angles[1], angles[2]
    da, db, dc = rates[0], rates[1], rates[2]
    sb, cb, sc, cc = jnp.sin(b), jnp.cos(b), jnp.sin(c), jnp.cos(c)
    return jnp.stack([da * sb * sc + db * cc, da * sb * cc - db * sc, da * cb + dc])


def _hat(w):
    """hat(w) v = w x v."""
    zero = jnp.zeros((), w.dtype)
    return jnp.array([[zero, -w[2], w[1]], [w[2], zero, -w[0]], [-w[1], w[0], zero]])


def euler_path(r, omega, start):
    """ZXZ angles and their rates along a sampled rotation: r (T, 3, 3) and body angular
    velocities omega (T, 3), from the angles ``start`` at the first sample.

    Each sample's angles are R's, beta = arccos(R_33) on the branch of sin(beta) that ``start``
    has ((alpha + pi, -beta, gamma + pi) is the same rotation: the Euler-Lagrange solution's
    tilt, too, stays on one side of the pole), alpha and gamma within pi of the last sample's
    (``start``'s turn at the first). That is the continuous path where no angle turns by pi or
    more between samples; the rotor's truth samples eight times per requested interval for it,
    as alpha and gamma swing by about pi where the tilt passes close to the pole. The rates
    invert :func:`body_angular_velocity`; they are ~ 1/sin(beta) near the pole and infinite
    on it.
    """
    alpha = jnp.arctan2(r[:, 0, 2], -r[:, 1, 2])
    beta = jnp.arccos(jnp.clip(r[:, 2, 2], -1.0, 1.0))
    gamma = jnp.arctan2(r[:, 2, 0], r[:, 2, 1])
    flip = jnp.sin(start[1]) < 0
    shift = jnp.where(flip, jnp.pi, 0.0)
    angles = jnp.stack([alpha + shift, jnp.where(flip, -beta, beta), gamma + shift], axis=-1)
    angles = angles.at[:, 0].set(jnp.unwrap(angles[:, 0])).at[:, 2].set(jnp.unwrap(angles[:, 2]))
    turns = jnp.round((start - angles[0]) / (2 * jnp.pi))
    angles = angles + 2 * jnp.pi * turns
    b, c = angles[:, 1], angles[:, 2]
    sb, cb, sc, cc = jnp.sin(b), jnp.cos(b), jnp.sin(c), jnp.cos(c)
    w1, w2, w3 = omega[:, 0], omega[:, 1], omega[:, 2]
    da = (w1 * sc + w2 * cc) / sb
    rates = jnp.stack([da, w1 * cc - w2 * sc, w3 - da * cb], axis=-1)
    return angles, rates


def _check_pole(beta: np.ndarray, name: str) -> None:
    near = np.abs(np.sin(beta)) < POLE
    if np.any(near):
        raise ValueError(
            f"{name}: ZXZ Euler angles are singular at sin(beta) = 0; initial states need "
            f"|sin(beta)| >= {POLE:g} (got {np.abs(np.sin(beta[near])).min():.3g})"
        )


def _canonical_beta(angles, rates):
    """The same rotation and angular velocity with beta in [0, pi): (a, b, c) with b < 0 is
    (a + pi, -b, c + pi), rates (a', -b', c') (as the reference's data after scipy's
    ``as_euler``)."""
    flip = angles[..., 1] < 0
    sign = jnp.where(flip, -1.0, 1.0)
    shift = jnp.where(flip, jnp.pi, 0.0)
    angles = jnp.stack(
        [angles[..., 0] + shift, sign * angles[..., 1], angles[..., 2] + shift], axis=-1
    )
    rates = rates.at[..., 1].multiply(sign)
    return angles, rates


class Gyroscope(AbstractSystem):
    """A heavy top: a rigid body on a fixed frictionless pivot under gravity, z up.

    q = ZXZ Euler angles (alpha, beta, gamma) of the body frame (R = Rz Rx Rz); the body's
    centre of mass sits at c = (0, 0, h) in the body frame from the pivot, so beta is the tilt of
    the symmetry axis from the vertical. With omega the body angular velocity,
    T = 1/2 omega^T I_c omega + 1/2 m |omega x c|^2, V = m g h cos(beta), I_c = diag(I_j) about
    the centre of mass, I_j = m (sum_i s_i - s_j) from the second moments s (the reference's
    T = 1/2 m |v_com|^2 + 1/2 sum_i m s_i |d e_i / dt|^2). Symmetric (I_x = I_y): energy and
    the angular momenta about the vertical (p_alpha) and the symmetry axis (p_gamma) are
    conserved.
    """

    inertia: tuple[float, float, float] = eqx.field(static=True, default=GYRO_INERTIA)
    com: tuple[float, float, float] = eqx.field(static=True, default=GYRO_COM)
    mass: float = eqx.field(static=True, default=MASS)
    g: float = eqx.field(static=True, default=G)
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(True,) * 3)
    name: str = eqx.field(static=True, default="gyroscope")
    n_args: int = eqx.field(static=True, default=0)

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 omega^T I_c omega + 1/2 m |omega x c|^2 (body frame)."""
        w = body_angular_velocity(q, qdot)
        v = jnp.cross(w, jnp.asarray(self.com))
        return 0.5 * jnp.sum(jnp.asarray(self.inertia) * w**2) + 0.5 * self.mass * jnp.dot(v, v)

    def potential_energy(self, q, args=None):
        """V = m g z_com, z_com = (R c)_z."""
        return self.mass * self.g * (rotation_matrix(q) @ jnp.asarray(self.com))[2]

    def positions(self, z):
        """The reference's body points, shape (4, 3): the centre of mass and com + e_i for the
        body axes e_i, pivot at the origin."""
        r = rotation_matrix(z[:3])
        x = r @ jnp.asarray(self.com)
        return jnp.concatenate([x[None], x[None] + r.T], axis=0)

    def check_states(self, z):
        _check_pole(np.asarray(z)[:, 1], self.name)

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """The reference's draw: angles and rates (U(0, 1) - 0.5) * 3, alpha' x 3,
        beta' x 0.2, spin gamma' = +-(N(0, 1) + 7) * 1.5 (random sign); beta < 0 is mapped to
        the same state with beta > 0. Draws with |sin(beta)| < 0.05 are redrawn (near-vertical
        tops, whose Euler rates blow up near the pole)."""
        return _redraw_near_pole(self._draw, key, n)

    def _draw(self, key, n):
        k_u, k_sign, k_spin = jax.random.split(key, 3)
        u = (jax.random.uniform(k_u, (n, 2, 3), dtype=jnp.float64) - 0.5) * 3.0
        sign = jnp.where(jax.random.bernoulli(k_sign, 0.5, (n,)), 1.0, -1.0)
        spin = sign * (jax.random.normal(k_spin, (n,), dtype=jnp.float64) + 7.0) * 1.5
        rates = u[:, 1] * jnp.array([3.0, 0.2, 1.0])
        rates = rates.at[:, 2].set(spin)
        angles, rates = _canonical_beta(u[:, 0], rates)
        return jnp.concatenate([angles, rates], axis=-1)


class Rotor(AbstractSystem):
    """A free rigid body without potential.

    q = (x, y, z, alpha, beta, gamma): the centre of mass and the ZXZ Euler angles of the body
    frame. T = 1/2 m |xdot|^2 + 1/2 omega^T I omega with I = diag(I_j), I_j = m (sum_i s_i -
    s_j) from the mesh's second moments s, V = 0. Energy, linear momentum m xdot and the spatial
    angular momentum R I omega (about the centre of mass) are conserved.

    Its ground truth integrates the frame, not the angles: (x, xdot, R, omega) with
    R' = R hat(omega), I omega' = I omega x omega (Euler's equations) and the drag -f m xdot,
    -f I omega, then reads the angles and their rates off each sample (:func:`euler_path`), as
    the reference read its Cartesian simulation. A free body's tilt passes the ZXZ pole at any
    distance, and the Euler-Lagrange equations in the angles need Euler rates ~ 1/sin(beta)
    there: one pass in a thousand draws took more than 10^6 Dopri8 steps, which the frame's
    equations, regular everywhere, take in a few hundred.
    """

    inertia: tuple[float, float, float] = eqx.field(static=True, default=ROTOR_INERTIA)
    mass: float = eqx.field(static=True, default=MASS)
    friction: float = eqx.field(static=True, default=0.0)
    angular: tuple[bool, ...] = eqx.field(static=True, default=(False,) * 3 + (True,) * 3)
    # at 1e-11 the frame's solve holds the angular momentum read back from the angles to 2e-10
    # (1e-7 of a component); at 1e-13, to the 1e-8 of its conservation test
    ground_truth_tol: ClassVar[float] = 1e-13
    # the angles are unwrapped on eight samples per requested interval (:func:`euler_path`)
    _truth_substeps: ClassVar[int] = 8
    name: str = eqx.field(static=True, default="rotor")
    n_args: int = eqx.field(static=True, default=0)

    def kinetic_energy(self, q, qdot, args=None):
        """T = 1/2 m |xdot|^2 + 1/2 omega^T I omega."""
        w = body_angular_velocity(q[3:], qdot[3:])
        rot = 0.5 * jnp.sum(jnp.asarray(self.inertia) * w**2)
        return 0.5 * self.mass * jnp.dot(qdot[:3], qdot[:3]) + rot

    def potential_energy(self, q, args=None):
        """V = 0."""
        return jnp.zeros((), dtype=q.dtype)

    def angular_momentum(self, z):
        """Spatial angular momentum about the centre of mass, R I omega_body."""
        w = body_angular_velocity(z[3:6], z[9:12])
        return rotation_matrix(z[3:6]) @ (jnp.asarray(self.inertia) * w)

    def positions(self, z):
        """The reference's body points, shape (4, 3): the centre of mass and com + e_i."""
        r = rotation_matrix(z[3:6])
        return jnp.concatenate([z[None, :3], z[None, :3] + r.T], axis=0)

    def check_states(self, z):
        _check_pole(np.asarray(z)[:, 4], self.name)

    def _truth_state(self, z0, args):
        del args
        q, qdot = z0[:6], z0[6:]
        return q[:3], qdot[:3], rotation_matrix(q[3:]), body_angular_velocity(q[3:], qdot[3:])

    def _truth_field(self, t, y, args):
        del t, args
        _, v, r, w = y
        inertia = jnp.asarray(self.inertia)
        dw = jnp.cross(inertia * w, w) / inertia - self.friction * w
        return v, -self.friction * v, r @ _hat(w), dw

    def _truth_to_z(self, ys, z0, args):
        del args
        x, v, r, w = ys
        angles, rates = euler_path(r, w, z0[3:6])
        return jnp.concatenate([x, angles, v, rates], axis=-1)

    @eqx.filter_jit
    def sample_initial(self, key, n: int):
        """The reference's draw: positions and rates of (com, Euler angles) clip(2 N(0, 1), -3,
        3), the com's x 0.1; beta < 0 is mapped to the same state with beta > 0. Draws with
        |sin(beta)| < 0.05 are redrawn."""
        return _redraw_near_pole(self._draw, key, n)

    def _draw(self, key, n):
        x = jnp.clip(2.0 * jax.random.normal(key, (n, 2, 6), dtype=jnp.float64), -3.0, 3.0)
        x = x.at[:, :, :3].multiply(0.1)
        angles, rates = _canonical_beta(x[:, 0, 3:], x[:, 1, 3:])
        return jnp.concatenate([x[:, 0, :3], angles, x[:, 1, :3], rates], axis=-1)


# Initial tilts closer than this to the pole are redrawn: a top or body starting there passes the
# Euler singularity at close range, with Euler rates of 1/sin(beta) (docs/studies/rigid_bodies.md).
START_POLE = 0.05


def _redraw_near_pole(draw, key, n):
    """``n`` states of ``draw`` whose |sin(beta)| >= START_POLE: draws 2n + 16 and keeps the first
    that qualify (each failing with probability < 0.04, so a shortfall is astronomically rare; a
    shortfall would repeat the last kept state)."""
    z = draw(key, 2 * n + 16)
    beta = z[:, z.shape[1] // 2 - 2]
    ok = jnp.abs(jnp.sin(beta)) >= START_POLE
    order = jnp.argsort(~ok, stable=True)
    return z[order[:n]]


def gyroscope(mass=MASS, g=G) -> Gyroscope:
    """The reference's gyroscope: mass 0.1, moments 100 x the mesh's second moments."""
    mass = check_positive("mass", mass)
    inertia = _inertia(mass, GYRO_SECOND_MOMENTS, GYRO_MOMENT_SCALE)
    return Gyroscope(inertia=inertia, com=GYRO_COM, mass=mass, g=check_real("g", g))


def rotor(mass=MASS) -> Rotor:
    """The reference's rotor: mass 0.1, the mesh's second moments."""
    mass = check_positive("mass", mass)
    return Rotor(inertia=_inertia(mass, ROTOR_SECOND_MOMENTS), mass=mass)
