"""The Deconstructing paper's experiments (Gruver et al. 2022, Figs. 2-9, Sec. 5): energy
(claim 1), symplectic regularisation (2), second-order structure (3), coordinates (4), damped
systems (5), the loss (6), Fig. 9's rigid bodies (13) and MuJoCo (16), and the diagnosis of the
plain HNN on the spring (claims 1 and 3). One folder per study; :mod:`bench.studies` imports
them in the report's order."""
