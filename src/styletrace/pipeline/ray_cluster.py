"""Joining Ray: a local instance on this machine, or a running cluster by its address.

    connect("local")            # start Ray here (the embedded default: one laptop is enough)
    connect("10.0.0.5:6379")    # join a cluster started with `ray start --head` on that machine

A process that already called `ray.init` (a script, the test suite) keeps its connection. Workers of
a local instance inherit this process's environment, PYTHONPATH included; the machines of a real
cluster need styletrace, Mitsuba and Dr.Jit installed in the same versions as here.
"""
from __future__ import annotations

import os

from styletrace.errors import UsageError

LOCAL = "local"


def ray_module():
    try:
        import ray
    except ImportError:
        raise UsageError(
            "rendering on Ray needs the 'ray' package: pip install 'styletrace[ray]'"
        ) from None
    return ray


def connect(cluster: str):
    """Ray, connected to a cluster; a process that called `ray.init` already keeps its connection.

    Args:
        cluster: "local" (start Ray here) or an address such as HOST:6379 or ray://HOST:10001.

    Returns:
        The `ray` module.

    Raises:
        UsageError: no `ray` package, a bad address, or a cluster that cannot be joined.
    """
    ray = ray_module()
    if not isinstance(cluster, str) or not cluster.strip():
        raise UsageError(
            f"bad cluster {cluster!r}: expected None, 'local' or a Ray address such as HOST:6379"
        )
    # every result the driver wants it gets (and raises); the only results left unread are those of
    # units cancelled on Ctrl-C, whose KeyboardInterrupt tracebacks Ray would otherwise print
    # at exit
    os.environ.setdefault("RAY_IGNORE_UNHANDLED_ERRORS", "1")
    if ray.is_initialized():
        return ray
    try:
        if cluster == LOCAL:
            ray.init(include_dashboard=False, logging_level="warning", log_to_driver=False)
        else:
            ray.init(address=cluster, logging_level="warning", log_to_driver=False)
    except (ConnectionError, ValueError, RuntimeError) as exc:
        lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
        raise UsageError(
            f"cannot join the Ray cluster at {cluster!r}: "
            f"{lines[0] if lines else type(exc).__name__}"
        ) from None
    return ray


def cpus() -> int:
    """The CPUs the joined cluster offers (all nodes)."""
    import ray
    return max(1, int(ray.cluster_resources().get("CPU", 1)))


__all__ = ["connect", "cpus", "ray_module", "LOCAL"]
