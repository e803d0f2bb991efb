"""Side-by-side checks: our training of a seed's model against the seed's own public code.

Each script here runs a seed's published code (a checkout the user clones themselves, passed
with ``--seed-code``; that code is never copied into or committed to this repository) beside the
suite's, on the same data and from the same initial parameters, and says where the two agree
and where they differ. ``python -m bench.sidebyside.lnn_seed``: the LNN seed's double pendulum;
``python -m bench.sidebyside.lnn_relativistic``: the LNN seed's relativistic particle (claim 7's
three models); ``python -m bench.sidebyside.hnn_seed``: the HNN seed's pixel pendulum;
``python -m bench.sidebyside.decon_hnn``: the paper's code, NODE+SO and the HNNs on the chain;
``python -m bench.sidebyside.decon_mujoco``: the paper's code, its MuJoCo models;
``python -m bench.sidebyside.decon_rigid``: the paper's code, Fig. 9's rigid bodies end to end
(docs/sidebyside.md).
"""
