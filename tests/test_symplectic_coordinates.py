"""Why claim 2's regulariser runs on canonical (q, p) states (issue 9).

The penalty ||J DF - (J DF)^T||_F^2 vanishes exactly for a Hamiltonian field dz/dt = J grad H.
The true chain-2 dynamics are Hamiltonian in (q, p) but not in (q, qdot): there the same
penalty is O(10-100), so regularising a model of (q, qdot) pulls it away from the truth. This
test evaluates the penalty on the TRUE field (float64, no learned model) in both coordinate
systems, and on a random linear field.
"""

import jax
import jax.numpy as jnp
import numpy as np

import systems  # noqa: F401  (enables float64)
from systems import make


def _penalty(field, zs) -> float:
    n = zs.shape[-1] // 2
    J = jnp.block([[jnp.zeros((n, n)), jnp.eye(n)], [-jnp.eye(n), jnp.zeros((n, n))]])

    def one(z):
        jdf = J @ jax.jacfwd(field)(z)
        return jnp.sum((jdf - jdf.T) ** 2)

    return float(jnp.mean(jax.vmap(one)(zs)))


def _states(system, n=4):
    key = jax.random.PRNGKey(0)
    return jnp.asarray(system.sample_initial(key, n), dtype=jnp.float64)


def test_true_chain_field_is_symplectic_in_q_p_and_not_in_q_qdot():
    chain = make("chain_pendulum", k=2)
    args = chain.default_args()
    zv = _states(chain)  # (q, qdot)
    dof = chain.dof

    def canonical(z):
        # dq/dt = M(q)^{-1} p, dp/dt = dL/dq at (q, qdot): Euler-Lagrange in (q, p)
        q, p = z[:dof], z[dof:]
        qdot = chain.velocity(q, p, args)
        pdot = jax.grad(chain.lagrangian, argnums=0)(q, qdot, args)
        return jnp.concatenate([qdot, pdot])

    zp = jax.vmap(lambda z: jnp.concatenate([z[:dof], chain.momentum(z, args)]))(zv)
    in_qp = _penalty(canonical, zp)
    in_qv = _penalty(lambda z: chain.vector_field(0.0, z, args), zv)
    assert in_qp < 1e-10, in_qp
    assert in_qv > 1.0, in_qv


def test_random_field_is_penalised():
    rng = np.random.default_rng(0)
    A = jnp.asarray(rng.standard_normal((4, 4)))
    zs = jnp.asarray(rng.standard_normal((8, 4)))
    assert _penalty(lambda z: jnp.tanh(A @ z), zs) > 0.1
