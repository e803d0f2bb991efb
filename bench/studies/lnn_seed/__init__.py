"""The LNN seed's experiments (Cranmer et al. 2020): the relativistic particle (claim 7), the
double pendulum's energy (no claim), and the double pendulum as the seed's notebook ran it
(``notebook``, claim 9). One folder per study; :mod:`bench.studies` imports them in the
report's order."""
