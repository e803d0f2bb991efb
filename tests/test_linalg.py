"""The models' small-matrix Cholesky factorisation and solves against LAPACK's (float64), for
values and for the gradients training takes through them, on both reading forms of the solve."""

import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np
import pytest

from models import cho_solve, cholesky
from models._linalg import _SPLIT, _UNROLL

SIZES = (1, 3, _SPLIT - 1, _SPLIT, _UNROLL, _UNROLL + 1)


def _spd(n, seed):
    r = np.random.default_rng(seed)
    m = r.standard_normal((n, n))
    return jnp.asarray(m @ m.T + n * np.eye(n)), jnp.asarray(r.standard_normal(n))


@pytest.mark.parametrize("n", SIZES)
def test_factor_and_solve_match_lapack(n):
    with jax.enable_x64():
        a, b = _spd(n, n)
        c = cholesky(a)
        np.testing.assert_allclose(c, np.linalg.cholesky(np.asarray(a)), rtol=1e-12, atol=1e-12)
        x = cho_solve(c, b)
        np.testing.assert_allclose(x, np.linalg.solve(np.asarray(a), np.asarray(b)), rtol=1e-10)


@pytest.mark.parametrize("n", SIZES)
def test_solve_gradients_match_lapack(n):
    # the gradient with respect to the factor and the right-hand side, batched as training
    # takes it, against the one through jax.scipy's triangular solves
    with jax.enable_x64():
        pairs = [_spd(n, s) for s in range(3)]
        cs = jnp.stack([jnp.linalg.cholesky(a) for a, _ in pairs])
        bs = jnp.stack([b for _, b in pairs])

        def loss(solve):
            return lambda c, b: jnp.sum(jnp.sin(jax.vmap(solve)(c, b)))

        ours = jax.grad(loss(cho_solve), argnums=(0, 1))(cs, bs)
        lapack = jax.grad(loss(lambda c, b: jsl.cho_solve((c, True), b)), argnums=(0, 1))(cs, bs)
        # only the lower triangle is read; jax.scipy's gradient reaches the upper one too
        lower = np.tril(np.ones((n, n)))
        np.testing.assert_allclose(ours[0] * lower, lapack[0] * lower, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(ours[1], lapack[1], rtol=1e-9, atol=1e-12)


def test_only_large_factors_are_read_by_one_split():
    # below _SPLIT the solve reads each entry where it uses it (the program, and so the float32
    # rounding, of the stored runs of small systems); from _SPLIT on, by one split
    def program(n):
        c, b = jnp.eye(n), jnp.ones(n)
        return str(jax.make_jaxpr(jax.grad(lambda c: jnp.sum(cho_solve(c, b))))(c))

    assert " split[" not in program(_SPLIT - 1) and " pad[" in program(_SPLIT - 1)
    assert " split[" in program(_SPLIT) and " pad[" not in program(_SPLIT)
