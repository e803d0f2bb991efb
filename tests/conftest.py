from bench.core._env import setup_process

setup_process()
