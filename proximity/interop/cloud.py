"""Distances from a point cloud on disk to a mesh: ``python -m proximity.cloud``.

::

    python -m proximity.cloud MESH POINTS -o OUT [--method M] [--signed [--sign S]]
                              [--closest-points] [--faces] [--chunk N]
                              [--scheduler ADDRESS | --workers N]

``MESH`` is any mesh trimesh reads (STL, OBJ, PLY, ...).  ``POINTS`` is an
``(N, 3)`` array: a ``.npy`` file (memory-mapped, never read whole), a
``.ply`` file (read whole, through trimesh), or a zarr array (a directory,
with zarr installed).  ``OUT`` is a ``.npy`` file or a ``.zarr`` directory:

- ``.npy``: the distances, float64 ``(N,)``; with ``--closest-points`` or
  ``--faces``, records with the fields ``distance``, ``point`` (3 floats)
  and ``face`` (int64, -1 where there is no answer), as asked;
- ``.zarr``: a group holding one array per field, chunked like the job.

With ``--signed`` the distances are signed, negative inside the mesh (the
field is then named ``signed_distance``), as
:meth:`proximity.TriangleMesh.signed_distance` gives them; ``--sign``
chooses how inside is told from outside, and implies ``--signed``: ``auto``
(the default, as that method's: the pseudonormal on a mesh that bounds a
solid, else the winding number, with a warning), ``pseudonormal`` (closed
manifold meshes) or ``winding`` (any mesh, slower).

Progress goes to stderr: a bar on a terminal, and where stderr is not one
(a pipe, a CI log, ``nohup``) a plain line every ten seconds or so; a last
line sums up the job.  ``--no-progress`` leaves only that line and the
warnings, each one line ``proximity.cloud: warning: ...`` (those the
library raises, such as a mesh that does not bound a solid, among them).

The job runs chunk by chunk (``--chunk`` rows at a time), so its memory is
bounded by the chunk, not by ``N``.  By default it runs in this process, on
every core, without Dask; ``--workers N`` starts a local Dask cluster of
``N`` processes and ``--scheduler ADDRESS`` sends the job to a running one
(whose workers must see the same files, at the same paths).

The output is written to ``OUT.partial`` and renamed to ``OUT`` once
complete: a job that stops midway (an error, Ctrl-C, SIGTERM) removes it,
and one that is killed leaves only ``OUT.partial``.  Rows of ``POINTS``
holding NaN or inf get NaN distances and a warning with their count;
chunks missing from a zarr array's store read as its fill value, with a
warning that counts them.

Bad input, an ``OUT`` that is one of the inputs (the same file, under any
name or link), and an ``OUT`` that cannot be written (a read-only
directory, a full disk) end the command with status 2 and an ``error:``
line on stderr, leaving no ``OUT.partial``.
"""

import argparse
import errno
import inspect
import json
import os
import shutil
import signal
import sys
import time
import warnings
from pathlib import Path

import numpy as np

NAME = "proximity.cloud"
CHUNK = 1_000_000
INSTALL = "pip install '.[scale]' in proximity's clone"
#: Seconds between progress lines where stderr is not a terminal.
LOG_EVERY = 10.0


class InputError(Exception):
    """Bad input: a message naming the file and what is wrong with it."""


class OutputError(Exception):
    """OUT cannot be written: a message naming it and why."""


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


def _ply_vertices(path):
    """The number of vertices the header of the ``.ply`` file at ``path``
    declares, or None where it declares none."""
    with open(path, "rb") as f:
        header = f.read(1 << 16)
    end = header.find(b"end_header")
    for line in header[: max(end, 0)].decode("ascii", "replace").splitlines():
        words = line.split()
        if words[:2] == ["element", "vertex"] and len(words) == 3 and words[2].isdigit():
            return int(words[2])
    return None


def _reasons(exc):
    """Why trimesh could not read a file: the errors of its chain (each raised while
    handling the one before, as trimesh turns from one reader to the next), first
    first, but the ImportErrors of the fallbacks it reached for last (a missing text
    decoder says nothing of the file), unless they are all there is."""
    chain = []
    while exc is not None and exc not in chain:
        chain.append(exc)
        exc = exc.__cause__ if exc.__cause__ is not None or exc.__suppress_context__ else exc.__context__
    told = [e for e in chain if not isinstance(e, ImportError)] or chain
    return "; then ".join(f"{type(e).__name__}: {e}" for e in reversed(told))


def read_mesh(path, merge=False):
    """The ``TriangleMesh`` of the mesh file at ``path``.

    With ``merge``, vertices of exactly the same coordinates are made one
    (an STL file repeats every vertex in each face that uses it), so that
    faces that meet share their edges, as the pseudonormal sign needs; the
    faces keep their order, and the surface is the same.
    """
    from ..shapes.mesh import TriangleMesh

    path = Path(path)
    if not path.exists():
        raise InputError(f"MESH {str(path)!r} does not exist")
    trimesh = _trimesh()
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds, all meaning "unreadable"
        raise InputError(f"cannot read MESH {str(path)!r} as a mesh (trimesh: {_reasons(exc)})") from None
    faces = getattr(loaded, "faces", None)
    if faces is None or len(faces) == 0:
        raise InputError(f"MESH {str(path)!r} holds no faces (an empty or truncated file, or a point cloud?)")
    vertices, faces = np.asarray(loaded.vertices), np.asarray(faces)
    if merge and len(vertices):
        vertices, index = np.unique(vertices, axis=0, return_inverse=True)
        faces = index.reshape(-1)[faces]
    try:
        return TriangleMesh(vertices, faces)
    except ValueError as exc:
        raise InputError(f"MESH {str(path)!r}: {exc}") from None


class Points:
    """Rows of a point file, read a chunk at a time; picklable (it holds the path).

    ``points[a:b]`` is a new float64 array of rows ``a`` to ``b``.
    ``missing_chunks`` counts the chunks absent from a zarr array's store,
    whose rows read as its ``fill_value`` (0 for the other kinds).
    """

    def __init__(self, path):
        path = Path(path)
        self.path = str(path)
        self.missing_chunks, self.chunks, self.fill_value = 0, 1, None
        if not path.exists():
            raise InputError(f"POINTS {self.path!r} does not exist")
        if _is_zarr(path):
            self.kind = "zarr"
            try:
                array = _zarr().open_array(self.path, mode="r")
            except Exception as exc:
                raise InputError(f"cannot read POINTS {self.path!r} as a zarr array: {exc}") from None
            initialized = getattr(array, "nchunks_initialized", None)
            if initialized is not None:
                self.chunks = int(array.nchunks)
                self.missing_chunks = self.chunks - int(initialized)
                self.fill_value = np.asarray(array.fill_value).item()
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
            # trimesh refuses a truncated binary file, but reads an ASCII one
            # that ends early as the rows it holds.
            declared = _ply_vertices(path)
            if declared is not None and declared != len(array):
                raise InputError(
                    f"POINTS {self.path!r} declares {declared:,} vertices but holds {len(array):,} "
                    "(a truncated file?)"
                )
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


def _fields(closest_points, faces, signed=False):
    names = ["signed_distance" if signed else "distance"]
    names += (["point"] if closest_points else []) + (["face"] if faces else [])
    return np.dtype([(n, {"point": ("f8", (3,)), "face": "i8"}.get(n, "f8")) for n in names])


def _clashes(target, source):
    """How writing ``target`` would replace or remove ``source`` (``"is"``:
    the same file, through symbolic or hard links; ``"holds"``: a directory
    that holds it), or None."""
    try:
        if os.path.samefile(target, source):
            return "is"
    except OSError:  # either does not exist
        return None
    if os.path.isdir(target) and Path(source).resolve().is_relative_to(Path(target).resolve()):
        return "holds"
    return None


def check_not_an_input(label, target, inputs):
    """Raise :class:`InputError` if ``target`` is or holds one of ``inputs``, ``(label, path)`` pairs."""
    for name, source in inputs:
        clash = _clashes(target, source)
        if clash is not None:
            what = " (the same file)" if clash == "is" else ""
            raise InputError(
                f"{label} {str(target)!r} {clash} {name} {str(source)!r}{what}: "
                "writing it would replace the input"
            )


class Output:
    """The output being written: ``OUT.partial`` until :meth:`commit`.

    Picklable (it holds paths): Dask workers write their own chunks.  A
    failure to write (a read-only directory, a full disk) raises
    :class:`OutputError`; :meth:`discard` then removes ``OUT.partial``.
    ``inputs`` are ``(label, path)`` pairs that neither ``OUT`` nor
    ``OUT.partial`` may be.
    """

    def __init__(self, path, n, dtype, chunk, inputs=()):
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
        if self.kind == "npy" and path.is_dir():
            raise InputError(f"OUT {self.path!r} is a directory")
        check_not_an_input("OUT", self.path, inputs)
        check_not_an_input("OUT's partial file", self.partial, inputs)
        try:
            self._create(n, chunk)
        except OSError as exc:
            self.discard()
            raise self._error(exc) from None

    def _create(self, n, chunk):
        self._remove(self.partial)
        if self.kind == "npy":
            # Distances alone as a plain array; more fields as records.
            stored = self.dtype[0] if len(self.dtype.names) == 1 else self.dtype
            header = {"descr": np.lib.format.dtype_to_descr(stored), "fortran_order": False, "shape": (n,)}
            with open(self.partial, "wb") as f:
                np.lib.format.write_array_header_1_0(f, header)
                self._offset = f.tell()
                size = self._offset + n * stored.itemsize
                f.truncate(size)
                _reserve(f, size)
        else:
            group = _zarr().open_group(self.partial, mode="w")
            for name in self.dtype.names:
                base, tail = self.dtype[name].base, self.dtype[name].shape
                fill = -1 if base.kind == "i" else float("nan")
                rows = (max(1, min(chunk, n)),)
                group.create_array(name, shape=(n,) + tail, chunks=rows + tail, dtype=base, fill_value=fill)

    def _error(self, exc):
        return OutputError(f"cannot write OUT {self.path!r}: {exc.strerror or exc}")

    @staticmethod
    def _remove(path):
        if os.path.isdir(path):
            shutil.rmtree(path)
        elif os.path.exists(path):
            os.remove(path)

    def write(self, start, table):
        """Write the records ``table`` as rows ``start`` on."""
        try:
            if self.kind == "npy":
                # Written through the file rather than a memory map, whose
                # writes to a full disk kill the process (SIGBUS).
                rows = table if len(self.dtype.names) > 1 else table[self.dtype.names[0]]
                rows = np.ascontiguousarray(rows)
                with open(self.partial, "r+b") as f:
                    f.seek(self._offset + start * rows.itemsize)
                    f.write(rows.view(np.uint8))
            else:
                group = _zarr().open_group(self.partial, mode="r+")
                for name in table.dtype.names:
                    group[name][start : start + len(table)] = table[name]
        except OSError as exc:
            raise self._error(exc) from None

    def commit(self):
        """Rename ``OUT.partial`` to ``OUT``, replacing what was there."""
        try:
            if self.kind == "npy":
                with open(self.partial, "rb+") as f:
                    os.fsync(f.fileno())
                os.replace(self.partial, self.path)
            else:
                self._remove(self.path)
                os.replace(self.partial, self.path)
        except OSError as exc:
            raise self._error(exc) from None

    def discard(self):
        """Remove the partial output, after a failure."""
        try:
            self._remove(self.partial)
        except OSError:
            pass  # nothing more to be done; the error that led here is reported


def _reserve(f, size):
    """Allocate the first ``size`` bytes of the open file ``f`` on disk where
    the system can, so that a disk too small for the output fails the job
    before its queries rather than after."""
    if not size or not hasattr(os, "posix_fallocate"):
        return
    try:
        os.posix_fallocate(f.fileno(), 0, size)
    except OSError as exc:
        if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
            raise
        # Not supported by this filesystem: a full disk fails the writes instead.


def _write_block(table, output, block_info=None):
    """Dask task: write one chunk of records; ``[[rows, NaN distances]]``."""
    start = block_info[0]["array-location"][0][0]
    output.write(start, table)
    return np.array([[len(table), int(np.isnan(table[table.dtype.names[0]]).sum())]], np.int64)


def _query(mesh, block, method, dtype, sign):
    """The records of ``block``, as :func:`proximity.dask.records` makes them."""
    from .dask import _records_block

    return _records_block(block, mesh, method, None, None, dtype, sign)


# --- Progress ------------------------------------------------------------------------------------


class _Line:
    """Progress on stderr without tqdm: one line redrawn on a terminal, else
    a plain line every :data:`LOG_EVERY` seconds and at the end, for logs."""

    def __init__(self, total, tty):
        self.total, self.done, self.start, self.last = total, 0, time.perf_counter(), None
        self.tty = tty

    def update(self, n):
        self.done += n
        now = time.perf_counter()
        if self.last is None:
            self.last = self.start
        if now - self.last < (0.2 if self.tty else LOG_EVERY) and self.done < self.total:
            return
        self.last = now
        elapsed = max(now - self.start, 1e-9)
        rate = self.done / elapsed
        share = 100 * self.done / max(self.total, 1)
        text = f"{NAME}: {self.done:,}/{self.total:,} points ({share:.0f}%, {rate:,.0f} points/s"
        if self.done < self.total and rate > 0:
            text += f", about {_duration((self.total - self.done) / rate)} left"
        text += ")"
        sys.stderr.write(("\r" + text) if self.tty else (text + "\n"))
        sys.stderr.flush()

    def close(self):
        if self.tty and self.done:
            sys.stderr.write("\n")


class _Quiet:
    def update(self, n):
        pass

    def close(self):
        pass


def _progress(total, show):
    """The progress display: ``show`` is True (a bar on a terminal, log lines
    elsewhere) or False (none)."""
    if not show:
        return _Quiet()
    tty = sys.stderr.isatty()
    if not tty:
        return _Line(total, tty=False)
    try:
        from tqdm import tqdm
    except ImportError:
        return _Line(total, tty=True)
    return tqdm(total=total, unit="points", unit_scale=True, desc=NAME, file=sys.stderr)


def _duration(seconds):
    """``"42 s"``, ``"3 min 5 s"``, ``"2 h 10 min"``."""
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60} min"


# --- Running -------------------------------------------------------------------------------------


def peak_rss():
    """Peak resident memory of this process, in bytes (None where not known)."""
    try:
        import resource
    except ImportError:  # Windows
        return None
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak if sys.platform == "darwin" else peak * 1024


def run_local(mesh, points, output, chunk, method, threads, bar, sign=None):
    """The embedded default: a loop over chunks in this process; the NaN count."""
    from ..runtime.threads import threads as limit

    nan = 0
    first = output.dtype.names[0]
    with limit(threads):
        for start in range(0, len(points), chunk):
            block = points[start : start + chunk]
            table = _query(mesh, block, method, output.dtype, sign)
            output.write(start, table)
            nan += int(np.isnan(table[first]).sum())
            bar.update(len(block))
    return nan


def run_dask(client, mesh, points, output, chunk, method, threads, bar, sign=None):
    """The job on a Dask cluster: one task per chunk reads, queries and writes it."""
    import dask.array as da
    from distributed import as_completed

    from .dask import records

    array = da.from_array(points, chunks=(chunk, 3), lock=False, asarray=False, meta=np.empty((0, 3)))
    table = records(mesh, array, method=method, threads=threads, fields=output.dtype.names, sign=sign)
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


#: What each ``--sign`` does, for the help.
SIGN_HELP = {
    "auto": "the pseudonormal on a mesh that bounds a solid, else the winding number, with a warning",
    "pseudonormal": "closed manifold meshes",
    "winding": "any mesh, slower",
}


def default_sign():
    """The sign of ``--signed`` without ``--sign``: ``TriangleMesh.signed_distance``'s own default."""
    from ..shapes.mesh import TriangleMesh

    return inspect.signature(TriangleMesh.signed_distance).parameters["sign"].default


def parser():
    """The command's argument parser."""
    from ..methods import REGISTRY
    from ..shapes.mesh import SIGNS

    default = default_sign()
    signs = "; ".join(f"{s} ({'the default: ' if s == default else ''}{SIGN_HELP[s]})" for s in SIGNS)

    parser = argparse.ArgumentParser(
        prog=f"python -m {NAME}",
        description="Distances, signed or not (and optionally closest points and faces) from the points "
        "of a file to a mesh, chunk by chunk, in this process or on a Dask cluster.",
    )
    parser.add_argument("mesh", metavar="MESH", help="a mesh file trimesh reads (STL, OBJ, PLY, ...)")
    parser.add_argument("points", metavar="POINTS", help="(N, 3) points: .npy, .ply, or a zarr array")
    parser.add_argument("-o", "--out", metavar="OUT", required=True, help="a .npy file or a .zarr directory")
    parser.add_argument("--method", default="robust", choices=list(REGISTRY), help="default: robust")
    parser.add_argument(
        "--signed", action="store_true", help="signed distances, negative inside the mesh (see --sign)"
    )
    parser.add_argument(
        "--sign",
        choices=SIGNS,
        help=f"how inside is told from outside (implies --signed): {signs}",
    )
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
        "--progress",
        action="store_true",
        default=True,
        help="show progress (the default): a bar on a terminal, else a line every few seconds",
    )
    parser.add_argument(
        "--no-progress", dest="progress", action="store_false", help="no progress; the last line stays"
    )
    parser.add_argument("--summary", metavar="FILE", help="write timings and peak memory as JSON to FILE")
    return parser


def parse(argv):
    """The command's arguments, checked."""
    command = parser()
    args = command.parse_args(argv)
    if args.sign is not None:
        args.signed = True
    elif args.signed:
        args.sign = default_sign()
    if args.chunk < 1:
        command.error(f"--chunk must be at least 1; got {args.chunk}")
    if args.workers is not None and args.workers < 1:
        command.error(f"--workers must be at least 1; got {args.workers}")
    if args.threads is not None and args.threads < 1:
        command.error(f"--threads must be at least 1; got {args.threads}")
    return args


def _check_sign(mesh, args):
    """Raise :class:`InputError` where ``--sign pseudonormal`` cannot sign this mesh (it is not closed)."""
    try:
        mesh.signed_distance(np.zeros((0, 3)), sign=args.sign)
    except ValueError as exc:
        raise InputError(f"MESH {args.mesh!r}: {exc}: pass --sign winding") from None


_WRITTEN = {
    "distance": "distances",
    "signed_distance": "signed distances",
    "point": "closest points",
    "face": "nearest faces",
}


def _summary_line(args, n, fields, seconds, query):
    """The last line: what was written, how many points, how fast."""
    what = ", ".join(_WRITTEN[name] for name in fields.names)
    rate = n / query if query > 0 else float("inf")
    sign = f", sign {args.sign}" if args.signed else ""
    return (
        f"{NAME}: wrote {what} of {n:,} points to {args.out} in {_duration(seconds)} "
        f"({rate:,.0f} points/s; method {args.method}{sign})"
    )


def _terminate(signum, frame):
    raise SystemExit(128 + signum)


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A warning as one line of the command's own, where Python would print the line of
    proximity's source that raised it."""
    print(f"{NAME}: warning: {' '.join(str(message).split())}", file=sys.stderr)


def _show_warnings_as_lines():
    """On the workers of a cluster the command started: their warnings as its lines too."""
    warnings.showwarning = _show_warning


def main(argv=None):
    """Run ``python -m proximity.cloud``; returns its exit status."""
    with warnings.catch_warnings():
        warnings.showwarning = _show_warning
        return _main(argv)


def _main(argv):
    args = parse(argv)
    started = time.perf_counter()
    output = None
    client = cluster = None
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        try:
            mesh = read_mesh(args.mesh, merge=args.signed)
            points = Points(args.points)
            inputs = [("MESH", args.mesh), ("POINTS", args.points)]
            if args.summary:
                check_not_an_input("--summary", args.summary, inputs)
            fields = _fields(args.closest_points, args.faces, args.signed)
            if args.signed:
                _check_sign(mesh, args)
            output = Output(args.out, len(points), fields, args.chunk, inputs)
        except (InputError, OutputError) as exc:
            print(f"{NAME}: error: {exc}", file=sys.stderr)
            return 2
        if points.missing_chunks:
            print(
                f"{NAME}: warning: {points.missing_chunks:,} of {points.chunks:,} chunks of POINTS "
                f"{args.points!r} are missing from its store: their rows read as its fill value "
                f"({points.fill_value!r})",
                file=sys.stderr,
            )
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
            if cluster is not None:  # the command's own workers, whose stderr is its own
                client.run(_show_warnings_as_lines)
        bar = _progress(len(points), args.progress)
        query_start = time.perf_counter()
        job = (mesh, points, output, args.chunk, args.method, args.threads, bar, args.sign)
        try:
            try:
                nan = run_local(*job) if client is None else run_dask(client, *job)
            finally:
                bar.close()
            query = time.perf_counter() - query_start
            output.commit()
        except OutputError as exc:
            print(f"{NAME}: error: {exc}", file=sys.stderr)
            return 2
        output = None
        print(_summary_line(args, len(points), fields, time.perf_counter() - started, query), file=sys.stderr)
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
                "sign": args.sign,
                "where": args.scheduler
                or (f"LocalCluster({args.workers})" if args.workers else "in-process"),
                "seconds": time.perf_counter() - started,
                "setup_seconds": setup,
                "query_seconds": query,
                "nan_rows": nan,
                "peak_rss_bytes": {"main": peak_rss(), "workers": workers},
            }
            try:
                Path(args.summary).write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
            except OSError as exc:
                print(
                    f"{NAME}: error: cannot write --summary {args.summary!r}: {exc.strerror or exc}",
                    file=sys.stderr,
                )
                return 2
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
    from proximity.interop.cloud import main as _main

    sys.exit(_main())
