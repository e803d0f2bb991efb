"""Registry of physical systems with exact float64 ground truth, and their datasets."""

import jax

jax.config.update("jax_enable_x64", True)
