"""Ordered maps, locally or on a Dask distributed cluster (docs/fitting.md, "Sweeps and Dask").

``map_ordered(fn, items, client)`` is ``[fn(x) for x in items]`` whether it runs here or on the
workers of ``client``: the results come back in item order, so a sweep or a fit that maps its
batches through it gives the same numbers with any number of workers. ``fn`` must be a
module-level function and the items plain data (text, numbers, numpy arrays): both are pickled.
"""

import reprlib

__all__ = ["map_ordered", "connect"]

_short = reprlib.Repr()
_short.maxstring = 60
_short.maxother = 60


def _failure(index, item, exc):
    return RuntimeError(
        f"map_ordered: item {index} ({_short.repr(item)}) failed: {type(exc).__name__}: {exc}")


def map_ordered(fn, items, client=None):
    """``[fn(x) for x in items]``, in item order.

    With ``client`` (a ``distributed.Client``) each item is one task (``client.map`` with
    ``pure=False``: every call runs, none is taken from a cache). An exception raised by ``fn``
    is raised here as RuntimeError naming the first failing item in item order, whichever
    worker finished first; the other tasks are cancelled.
    """
    if not callable(fn):
        raise TypeError(f"map_ordered: fn must be callable, not {type(fn).__name__}")
    items = list(items)
    if client is None:
        results = []
        for i, item in enumerate(items):
            try:
                results.append(fn(item))
            except Exception as exc:
                raise _failure(i, item, exc) from exc
        return results
    if not (hasattr(client, "map") and hasattr(client, "gather")):
        raise TypeError("map_ordered: client must be a distributed.Client or None, "
                        f"not {type(client).__name__}")
    if not items:
        return []
    futures = client.map(fn, items, pure=False)
    try:
        from distributed import wait
        wait(futures)
        for i, future in enumerate(futures):
            if future.status == "error":
                exc = future.exception()
                raise _failure(i, items[i], exc) from exc
            if future.status != "finished":
                raise RuntimeError(f"map_ordered: item {i} ({_short.repr(items[i])}) "
                                   f"was {future.status} on the cluster")
        return client.gather(futures)
    finally:
        client.cancel(futures)


def connect(address, timeout=10):
    """A ``distributed.Client`` of the scheduler at ``address`` (``tcp://host:8786``);
    RuntimeError in one line when none answers within ``timeout`` seconds."""
    from distributed import Client
    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError) as exc:
        raise RuntimeError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
