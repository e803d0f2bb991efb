"""A local Ray instance whose processes are not forked from the sweep's process.

``ray.init()`` starts the local instance's processes (GCS server, raylet, monitors) from the
calling process with ``subprocess.Popen(..., preexec_fn=...)``: a fork that runs Python in the
child before it execs. A sweep's process has JAX's backend up by then (building a run
configuration builds its system), so JAX's threads are running and its fork handler warns
that the fork may deadlock, rightly. :func:`start` runs ``ray.init()`` in a spawned helper
process (fork-exec without Python in between: no fork handler runs) that never starts a JAX
backend; the sweep then connects to it by address, which starts no process.
"""

from __future__ import annotations

import multiprocessing as mp
import os

START_SECONDS = 180.0  # a local instance takes ~3 s on an idle machine; far more under load
AUTH_MODE_ENV = "RAY_AUTH_MODE"


def auth_ready(fresh: bool) -> bool:
    """Whether a :class:`LocalHead` can serve this process: Ray's authentication mode is set,
    or ray is not imported yet (``fresh``), so that setting it now (as ``ray.init()`` would for
    an instance it starts) takes effect when ray is imported."""
    if AUTH_MODE_ENV in os.environ:
        return True
    if fresh:
        os.environ[AUTH_MODE_ENV] = "token"
        return True
    return False


class LocalHead:
    """A local Ray instance hosted by a spawned helper; :attr:`address` is its GCS address."""

    def __init__(self, cores: int):
        # ray.init() turns token authentication on for a local instance it starts; a driver
        # connecting by address does not, and Ray reads the mode when it is imported: the
        # caller sets AUTH_MODE_ENV before this process first imports ray (:func:`auth_ready`)
        if AUTH_MODE_ENV not in os.environ:
            raise ImportError(f"{AUTH_MODE_ENV} must be set before ray is imported")
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_host, args=(child, cores), daemon=True, name="ray-head")
        self._proc.start()
        child.close()
        if not self._conn.poll(START_SECONDS):
            self.stop()
            raise RuntimeError(f"a local Ray instance did not start in {START_SECONDS:.0f} s")
        try:
            ok, what = self._conn.recv()
        except EOFError:
            ok, what = False, f"its helper process died (exit code {self._proc.exitcode})"
        if not ok:
            self.stop()
            raise RuntimeError(f"a local Ray instance did not start: {what}")
        self.address: str = what

    def stop(self) -> None:
        """Shut the instance down and end the helper (waits up to 60 s, then terminates it)."""
        try:
            self._conn.send(None)
        except (OSError, ValueError):  # the helper is gone already
            pass
        self._proc.join(60)
        if self._proc.is_alive():
            self._proc.terminate()
            self._proc.join(10)
        self._conn.close()


def _host(conn, cores: int) -> None:
    """The helper: start the instance, send its address, keep it until told to stop (or the
    sweep's process goes away: the pipe closes)."""
    import ray

    try:
        ray.init(num_cpus=cores, include_dashboard=False, log_to_driver=False)
    except Exception as e:  # noqa: BLE001 - reported to the sweep, one line
        conn.send((False, f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"))
        return
    conn.send((True, ray.get_runtime_context().gcs_address))
    try:
        conn.recv()
    except EOFError:
        pass
    ray.shutdown()
