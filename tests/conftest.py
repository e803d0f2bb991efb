from bench._env import configure_threads

configure_threads()
