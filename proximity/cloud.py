"""Distances from a point cloud on disk to a mesh: ``python -m proximity.cloud``.

::

    python -m proximity.cloud MESH POINTS -o OUT [--method M] [--closest-points] [--faces]
                              [--chunk N] [--scheduler ADDRESS | --workers N]

``MESH`` is any mesh trimesh reads (STL, OBJ, PLY, ...).  ``POINTS`` is an
``(N, 3)`` array: a ``.npy`` file (memory-mapped, never read whole), a
``.ply`` file (read whole, through trimesh), or a zarr array (a directory,
with zarr installed).  ``OUT`` is a ``.npy`` file or a ``.zarr`` directory:

- ``.npy``: the distances, float64 ``(N,)``; with ``--closest-points`` or
  ``--faces``, records with the fields ``distance``, ``point`` (3 floats)
  and ``face`` (int64, -1 where there is no answer), as asked;
- ``.zarr``: a group holding one array per field, chunked like the job.

The job runs chunk by chunk (``--chunk`` rows at a time), so its memory is
bounded by the chunk, not by ``N``.  By default it runs in this process, on
every core, without Dask; ``--workers N`` starts a local Dask cluster of
``N`` processes and ``--scheduler ADDRESS`` sends the job to a running one
(whose workers must see the same files, at the same paths).

The output is written to ``OUT.partial`` and renamed to ``OUT`` once
complete: a job that stops midway (an error, Ctrl-C, SIGTERM) removes it,
and one that is killed leaves only ``OUT.partial``.  Rows of ``POINTS``
holding NaN or inf get NaN distances and a warning with their count.
"""

import argparse
import json
import os
import shutil
import signal
import sys
import time
from pathlib import Path

import numpy as np

NAME = "proximity.cloud"
CHUNK = 1_000_000
INSTALL = "pip install 'proximity3d[scale]'"


class InputError(Exception):
    """Bad input: a message naming the file and what is wrong with it."""


# --- Input ---------------------------------------------------------------------------------------


def _trimesh():
    try:
        import trimesh
    except ImportError:
        raise InputError(f"reading meshes and .ply files needs trimesh: {INSTALL}") from None
    return trimesh


def _zarr():
    try:
        import zarr
    except ImportError:
        raise InputError(f"zarr arrays need zarr 3 (on Python 3.11 or later): {INSTALL}") from None
    return zarr


def _is_zarr(path):
    markers = ("zarr.json", ".zarray")  # zarr 3, zarr 2
    return path.suffix == ".zarr" or (path.is_dir() and any((path / m).exists() for m in markers))


def read_mesh(path):
    """The ``TriangleMesh`` of the mesh file at ``path``."""
    import proximity

    path = Path(path)
    if not path.exists():
        raise InputError(f"MESH {str(path)!r} does not exist")
    trimesh = _trimesh()
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds, all meaning "unreadable"
        raise InputError(f"cannot read MESH {str(path)!r} as a mesh ({type(exc).__name__}: {exc})") from None
    faces = getattr(loaded, "faces", None)
    if faces is None or len(faces) == 0:
        raise InputError(f"MESH {str(path)!r} holds no faces (an empty or truncated file, or a point cloud?)")
    try:
        return proximity.TriangleMesh(np.asarray(loaded.vertices), np.asarray(faces))
    except ValueError as exc:
        raise InputError(f"MESH {str(path)!r}: {exc}") from None


class Points:
    """Rows of a point file, read a chunk at a time; picklable (it holds the path).

    ``points[a:b]`` is a new float64 array of rows ``a`` to ``b``.
    """

    def __init__(self, path):
        path = Path(path)
        self.path = str(path)
        if not path.exists():
            raise InputError(f"POINTS {self.path!r} does not exist")
        if _is_zarr(path):
            self.kind = "zarr"
            try:
                array = _zarr().open_array(self.path, mode="r")
            except Exception as exc:
                raise InputError(f"cannot read POINTS {self.path!r} as a zarr array: {exc}") from None
            self._array = None
        elif path.suffix == ".npy":
            self.kind = "npy"
            try:
                array = np.load(self.path, mmap_mode="r")
            except Exception as exc:
                raise InputError(f"cannot read POINTS {self.path!r} as a .npy file: {exc}") from None
            if not isinstance(array, np.ndarray):
                raise InputError(f"POINTS {self.path!r} is not a .npy array")
            self._array = None
        elif path.suffix == ".ply":
            self.kind = "ply"
            try:
                loaded = _trimesh().load(path, process=False)
            except InputError:
                raise
            except Exception as exc:
                raise InputError(f"cannot read POINTS {self.path!r} as a .ply file: {exc}") from None
            array = np.asarray(getattr(loaded, "vertices", np.empty((0, 0))))
            self._array = array
        else:
            raise InputError(f"POINTS {self.path!r}: expected a .npy or .ply file or a zarr array")
        if array.dtype.kind not in "iuf":
            raise InputError(f"POINTS {self.path!r} must hold numbers; got dtype {array.dtype}")
        if array.ndim != 2 or array.shape[1] != 3:
            raise InputError(f"POINTS {self.path!r} must have shape (N, 3); got shape {array.shape}")
        self.shape = tuple(int(n) for n in array.shape)
        self.dtype = np.dtype(np.float64)
        self.ndim = 2

    def __len__(self):
        return self.shape[0]

    def __getstate__(self):
        return {k: v for k, v in vars(self).items() if k != "_array" or self.kind == "ply"}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self.__dict__.setdefault("_array", None)

    def __getitem__(self, key):
        if self.kind == "ply":
            source = self._array
        elif self.kind == "npy":
            # A mapping per chunk: the pages read leave this process with it.
            source = np.load(self.path, mmap_mode="r")
        else:
            source = _zarr().open_array(self.path, mode="r")
        return np.array(source[key], dtype=np.float64)


# --- Output --------------------------------------------------------------------------------------


def _fields(closest_points, faces):
    names = ["distance"] + (["point"] if closest_points else []) + (["face"] if faces else [])
    return np.dtype([(n, {"point": ("f8", (3,)), "face": "i8"}.get(n, "f8")) for n in names])


class Output:
    """The output being written: ``OUT.partial`` until :meth:`commit`.

    Picklable (it holds paths): Dask workers write their own chunks.
    """

    def __init__(self, path, n, dtype, chunk):
        path = Path(path)
        self.path = str(path)
        self.partial = str(path) + ".partial"
        self.dtype = dtype
        if path.suffix == ".npy":
            self.kind = "npy"
        elif path.suffix == ".zarr":
            self.kind = "zarr"
        else:
            raise InputError(f"OUT {self.path!r}: expected a .npy file or a .zarr directory")
        if not path.parent.is_dir():
            raise InputError(f"OUT {self.path!r}: directory {str(path.parent)!r} does not exist")
        self._remove(self.partial)
        if self.kind == "npy":
            # Distances alone as a plain array; more fields as records.
            stored = np.dtype(np.float64) if dtype.names == ("distance",) else dtype
            out = np.lib.format.open_memmap(self.partial, mode="w+", dtype=stored, shape=(n,))
            del out  # sized on disk; chunks map their own rows
        else:
            group = _zarr().open_group(self.partial, mode="w")
            for name in dtype.names:
                base, tail = dtype[name].base, dtype[name].shape
                fill = -1 if base.kind == "i" else float("nan")
                rows = (max(1, min(chunk, n)),)
                group.create_array(name, shape=(n,) + tail, chunks=rows + tail, dtype=base, fill_value=fill)

    @staticmethod
    def _remove(path):
        if os.path.isdir(path):
            shutil.rmtree(path)
        elif os.path.exists(path):
            os.remove(path)

    def write(self, start, table):
        """Write the records ``table`` as rows ``start`` on."""
        stop = start + len(table)
        if self.kind == "npy":
            out = np.load(self.partial, mmap_mode="r+")
            if out.dtype.names:
                out[start:stop] = table
            else:
                out[start:stop] = table["distance"]
            out.flush()
            del out
        else:
            group = _zarr().open_group(self.partial, mode="r+")
            for name in table.dtype.names:
                group[name][start:stop] = table[name]

    def commit(self):
        """Rename ``OUT.partial`` to ``OUT``, replacing what was there."""
        if self.kind == "npy":
            with open(self.partial, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(self.partial, self.path)
        else:
            self._remove(self.path)
            os.replace(self.partial, self.path)

    def discard(self):
        self._remove(self.partial)


def _write_block(table, output, block_info=None):
    """Dask task: write one chunk of records; ``[[rows, NaN distances]]``."""
    start = block_info[0]["array-location"][0][0]
    output.write(start, table)
    return np.array([[len(table), int(np.isnan(table["distance"]).sum())]], np.int64)


def _query(mesh, block, method, dtype):
    """The records of ``block``."""
    out = np.empty(len(block), dtype)
    if dtype.names == ("distance",):
        out["distance"] = mesh.distance(block, method=method)
        return out
    r = mesh.closest_point(block, method=method)
    for name in dtype.names:
        out[name] = getattr(r, name)
    return out


# --- Progress ------------------------------------------------------------------------------------


class _Line:
    """A progress line on stderr, for when tqdm is not installed."""

    def __init__(self, total):
        self.total, self.done, self.start, self.last = total, 0, time.perf_counter(), 0.0
        self.tty = sys.stderr.isatty()

    def update(self, n):
        self.done += n
        now = time.perf_counter()
        if now - self.last < (0.2 if self.tty else 5.0) and self.done < self.total:
            return
        self.last = now
        rate = self.done / max(now - self.start, 1e-9)
        share = 100 * self.done / max(self.total, 1)
        text = f"{NAME}: {self.done:,}/{self.total:,} points ({share:.0f}%, {rate:,.0f} points/s)"
        sys.stderr.write(("\r" + text) if self.tty else (text + "\n"))
        sys.stderr.flush()

    def close(self):
        if self.tty:
            sys.stderr.write("\n")


class _Quiet:
    def update(self, n):
        pass

    def close(self):
        pass


def _progress(total, show):
    if not show:
        return _Quiet()
    try:
        from tqdm import tqdm
    except ImportError:
        return _Line(total)
    return tqdm(total=total, unit="points", unit_scale=True, desc=NAME, file=sys.stderr)


# --- Running -------------------------------------------------------------------------------------


def peak_rss():
    """This process's peak resident memory, in bytes (None where not known)."""
    try:
        import resource
    except ImportError:  # Windows
        return None
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak if sys.platform == "darwin" else peak * 1024


def run_local(mesh, points, output, chunk, method, threads, bar):
    """The embedded default: a loop over chunks in this process; the NaN count."""
    import proximity

    nan = 0
    with proximity.threads(threads):
        for start in range(0, len(points), chunk):
            block = points[start : start + chunk]
            table = _query(mesh, block, method, output.dtype)
            output.write(start, table)
            nan += int(np.isnan(table["distance"]).sum())
            bar.update(len(block))
    return nan


def run_dask(client, mesh, points, output, chunk, method, threads, bar):
    """The job on a Dask cluster: one task per chunk reads, queries and writes it."""
    import dask.array as da
    from distributed import as_completed

    import proximity.dask

    array = da.from_array(points, chunks=(chunk, 3), lock=False, asarray=False, meta=np.empty((0, 3)))
    table = proximity.dask.records(mesh, array, method=method, threads=threads, fields=output.dtype.names)
    written = table.map_blocks(
        _write_block,
        output,
        new_axis=1,
        chunks=((1,) * table.numblocks[0], (2,)),
        dtype=np.int64,
        meta=np.empty((0, 2), np.int64),
    )
    futures = client.compute(list(written.to_delayed().ravel()))
    nan = 0
    try:
        for future in as_completed(futures):
            rows, bad = future.result()[0]
            nan += int(bad)
            bar.update(int(rows))
    except BaseException:
        client.cancel(futures)
        raise
    return nan


def _worker_peak_rss():
    return peak_rss()


def parse(argv):
    from .methods import REGISTRY

    parser = argparse.ArgumentParser(
        prog=f"python -m {NAME}",
        description="Distances (and optionally closest points and faces) from the points of a file "
        "to a mesh, chunk by chunk, in this process or on a Dask cluster.",
    )
    parser.add_argument("mesh", metavar="MESH", help="a mesh file trimesh reads (STL, OBJ, PLY, ...)")
    parser.add_argument("points", metavar="POINTS", help="(N, 3) points: .npy, .ply, or a zarr array")
    parser.add_argument("-o", "--out", metavar="OUT", required=True, help="a .npy file or a .zarr directory")
    parser.add_argument("--method", default="robust", choices=list(REGISTRY), help="default: robust")
    parser.add_argument("--closest-points", action="store_true", help="also write the closest points")
    parser.add_argument("--faces", action="store_true", help="also write the index of the nearest face")
    parser.add_argument(
        "--chunk", type=int, default=CHUNK, metavar="N", help=f"rows per chunk (default {CHUNK:,})"
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS", help="run on the Dask cluster at ADDRESS")
    where.add_argument("--workers", type=int, metavar="N", help="run on a local Dask cluster of N processes")
    parser.add_argument(
        "--threads", type=int, metavar="N", help="Numba threads per chunk (default: cores per running chunk)"
    )
    parser.add_argument(
        "--progress", action="store_true", default=None, help="show progress even if not a TTY"
    )
    parser.add_argument("--no-progress", dest="progress", action="store_false", help="never show progress")
    parser.add_argument("--summary", metavar="FILE", help="write timings and peak memory as JSON to FILE")
    args = parser.parse_args(argv)
    if args.chunk < 1:
        parser.error(f"--chunk must be at least 1; got {args.chunk}")
    if args.workers is not None and args.workers < 1:
        parser.error(f"--workers must be at least 1; got {args.workers}")
    if args.threads is not None and args.threads < 1:
        parser.error(f"--threads must be at least 1; got {args.threads}")
    return args


def _terminate(signum, frame):
    raise SystemExit(128 + signum)


def main(argv=None):
    args = parse(argv)
    show = sys.stderr.isatty() if args.progress is None else args.progress
    started = time.perf_counter()
    output = None
    client = cluster = None
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        try:
            mesh = read_mesh(args.mesh)
            points = Points(args.points)
            output = Output(args.out, len(points), _fields(args.closest_points, args.faces), args.chunk)
        except InputError as exc:
            print(f"{NAME}: error: {exc}", file=sys.stderr)
            return 2
        setup = time.perf_counter() - started
        if args.scheduler or args.workers:
            try:
                from distributed import Client, LocalCluster
            except ImportError:
                print(f"{NAME}: error: --scheduler and --workers need Dask: {INSTALL}", file=sys.stderr)
                return 2
            if args.workers:
                cluster = LocalCluster(
                    n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=":0"
                )
            client = Client(args.scheduler or cluster)
        bar = _progress(len(points), show)
        query_start = time.perf_counter()
        try:
            if client is None:
                nan = run_local(mesh, points, output, args.chunk, args.method, args.threads, bar)
            else:
                nan = run_dask(client, mesh, points, output, args.chunk, args.method, args.threads, bar)
        finally:
            bar.close()
        query = time.perf_counter() - query_start
        output.commit()
        output = None
        if nan:
            print(
                f"{NAME}: warning: {nan:,} of {len(points):,} rows of POINTS {args.points!r} "
                "hold NaN or inf: their distances are NaN",
                file=sys.stderr,
            )
        if args.summary:
            workers = client.run(_worker_peak_rss) if client is not None and args.workers else {}
            summary = {
                "points": len(points),
                "chunk": args.chunk,
                "method": args.method,
                "where": args.scheduler
                or (f"LocalCluster({args.workers})" if args.workers else "in-process"),
                "seconds": time.perf_counter() - started,
                "setup_seconds": setup,
                "query_seconds": query,
                "nan_rows": nan,
                "peak_rss_bytes": {"main": peak_rss(), "workers": workers},
            }
            Path(args.summary).write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
        return 0
    except KeyboardInterrupt:
        print(f"{NAME}: interrupted; no output written", file=sys.stderr)
        return 130
    finally:
        if output is not None:
            output.discard()
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
        signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    # From the module, not __main__: Dask workers import what they run by name.
    from proximity.cloud import main as _main

    sys.exit(_main())
