"""Map a function over surfaces: here (in order), in local processes, or on a Dask cluster.

The gallery and the sweep mesh many surfaces, each independent of the
others.  :func:`map_ordered` runs them and returns the results in the
order of the input whatever order they finish in, so that the files and
records written from them are the same bytes however they ran.

``scheduler``:

- ``None``: ``jobs`` local processes (``spawn``: a clean interpreter per
  worker; ``fork`` would copy the parent's threads and matplotlib state),
  or this process when ``jobs`` is 1;
- ``"local"``: a :class:`dask.distributed.LocalCluster` of ``jobs`` worker
  processes of one thread each on this machine;
- an address (``"tcp://10.0.0.5:8786"``): the Dask scheduler of a running
  cluster.  The workers need singmesh installed (the same version), and can
  be given further modules with ``upload``;
- a :class:`dask.distributed.Client` already connected (a notebook's): used
  as it is, and left open.

Worker processes rather than threads: mesh() limits BLAS per process, and
``warnings.catch_warnings`` and matplotlib's pyplot are not thread-safe.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any, Callable, Sequence

from .extras import require


def map_ordered(fn: Callable[[Any], Any], items: Sequence[Any], *, jobs: int = 1,
                scheduler: Any = None, upload: Sequence[str | Path] = (),
                on_done: Callable[[int, Any], None] | None = None,
                capture: bool = False) -> list[Any]:
    """``[fn(item) for item in items]``, run in parallel as asked, in the input order.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled by reference).
    items : sequence
        Its arguments, one call each (picklable).
    jobs : int
        Local processes (``scheduler=None``) or the LocalCluster's workers
        (``scheduler="local"``); not used with an address.
    scheduler : str or dask.distributed.Client, optional
        None, ``"local"``, the address of a Dask scheduler or a Client (see
        the module docstring).
    upload : sequence of paths
        Python files sent to the Dask workers (``Client.upload_file``), for
        ``fn`` defined outside an installed package (the gallery's
        ``gallery_lib.py``).
    on_done : callable, optional
        ``on_done(index, result)`` as each call finishes (a progress bar);
        called in the order they finish.
    capture : bool
        An exception of a call (or its worker's death) is put in its place
        in the list, not raised.

    Returns
    -------
    list
        The results in the order of ``items``.
    """
    items = list(items)
    if scheduler is not None:
        return _on_dask(fn, items, max(1, jobs), scheduler, upload, on_done, capture)
    results: list[Any] = [None] * len(items)
    if jobs <= 1 or len(items) <= 1:
        for i, item in enumerate(items):
            results[i] = _call(fn, item, capture)
            if on_done is not None:
                on_done(i, results[i])
        return results
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(jobs, len(items)), mp_context=ctx) as pool:
        futures = {pool.submit(fn, item): i for i, item in enumerate(items)}
        for fut in as_completed(futures):
            i = futures[fut]
            results[i] = _result(fut, capture)
            if on_done is not None:
                on_done(i, results[i])
    return results


def _call(fn: Callable[[Any], Any], item: Any, capture: bool) -> Any:
    if not capture:
        return fn(item)
    try:
        return fn(item)
    except Exception as exc:
        return exc


def _result(future, capture: bool) -> Any:
    if not capture:
        return future.result()
    try:
        return future.result()
    except Exception as exc:  # the call raised, or its worker died (crash, out of memory)
        return exc


def _on_dask(fn, items: list, jobs: int, scheduler: str, upload, on_done, capture: bool) -> list:
    """:func:`map_ordered` through ``dask.distributed``."""
    require("--scheduler (Dask)", ["dask", "distributed"], extra="dask")
    from distributed import Client, LocalCluster, as_completed as dask_completed

    cluster = None
    own = True  # a client made here is closed here
    if isinstance(scheduler, Client):
        client, own = scheduler, False
    elif scheduler == "local":
        # Processes, one thread each (see the module docstring); no
        # dashboard: its port may be taken, and nobody looks at it here.
        cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=30)
        except (OSError, TimeoutError, ValueError) as exc:
            from .errors import SurfaceError

            raise SurfaceError(f"cannot reach the Dask scheduler {scheduler}: {exc}") from None
    try:
        for path in upload:
            client.upload_file(str(path))
        # pure=False: each call runs (the same item twice is two frames).
        futures = client.map(fn, items, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        results: list[Any] = [None] * len(items)
        for fut in dask_completed(futures):
            i = index[fut.key]
            results[i] = _result(fut, capture)
            if on_done is not None:
                on_done(i, results[i])
        return results
    finally:
        if own:
            client.close()
        if cluster is not None:
            cluster.close()
