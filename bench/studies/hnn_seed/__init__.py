"""The HNN seed's experiments (Greydanus et al. 2019): its own tasks from states (``tasks``,
claim 10), the pixel pendulum (``pixels``: claim 11, and the VIN seed's pixel forecasts of
claim 12, which share its data and protocol), three-body (14) and the real pendulum (15). One
folder per study; :mod:`bench.studies` imports them in the report's order."""
