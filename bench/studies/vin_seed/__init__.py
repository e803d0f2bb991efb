"""The VIN seed's experiments (Saemundsson et al. 2020): the VIN against a ResNet from states
(claim 8) and the pixel pendulum as its blog and its authors' code ran it (``vin_blog``, claim
12's second reading; its first lives with the pixel pendulum, ``bench.studies.hnn_seed.pixels``).
One folder per study; :mod:`bench.studies` imports them in the report's order."""
