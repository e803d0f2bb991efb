from bench.core._env import configure_compilation_cache, configure_threads

configure_threads()
configure_compilation_cache()
