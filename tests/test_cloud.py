"""python -m proximity.cloud: distances from a point file to a mesh file,
chunk by chunk, in this process or on Dask, equal bit for bit to the
in-memory query; bad input named; no complete-looking output from a job
that stopped."""

import json
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from proximity import cloud  # noqa: E402

N = 20_000
CHUNK = "3000"  # does not divide N


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cloud")
    sphere = trimesh.creation.icosphere(subdivisions=3)
    paths = {}
    for suffix in ("stl", "obj", "ply"):
        paths[suffix] = folder / f"sphere.{suffix}"
        sphere.export(paths[suffix])
    points = np.random.default_rng(0).normal(size=(N, 3)) * 1.3
    points[[5, 17, 9000]] = [[np.nan, 0, 0], [0, np.inf, 0], [np.nan, np.nan, np.nan]]
    paths["npy"] = folder / "points.npy"
    np.save(paths["npy"], points)
    paths["points"] = points
    return paths


def _run(*args):
    return cloud.main([str(a) for a in args])


def _expected(mesh_path, points):
    return cloud.read_mesh(mesh_path).closest_point(points)


@pytest.mark.parametrize("mesh", ["stl", "obj", "ply"])
def test_distances_of_an_npy_cloud_equal_the_in_memory_query(files, mesh, tmp_path, capsys):
    out = tmp_path / "d.npy"
    assert _run(files[mesh], files["npy"], "-o", out, "--chunk", CHUNK) == 0
    got = np.load(out)
    expected = _expected(files[mesh], files["points"]).distance
    assert got.dtype == np.float64 and got.tobytes() == expected.tobytes()
    assert not os.path.exists(str(out) + ".partial")
    lines = capsys.readouterr().err.splitlines()
    # Where stderr is not a terminal: progress as plain lines, the last line of
    # the job, and the warning about the three bad rows.
    assert lines[-3].startswith("proximity.cloud: 20,000/20,000 points (100%, ")
    assert lines[-2].startswith(f"proximity.cloud: wrote distances of 20,000 points to {out} in ")
    assert lines[-1] == (
        f"proximity.cloud: warning: 3 of 20,000 rows of POINTS {str(files['npy'])!r} hold NaN or inf: "
        "their distances are NaN"
    )
    assert np.isnan(got[[5, 17, 9000]]).all() and np.isfinite(np.delete(got, [5, 17, 9000])).all()


def test_closest_points_and_faces_as_records(files, tmp_path):
    out = tmp_path / "r.npy"
    args = ["--closest-points", "--faces", "--method", "certified", "--chunk", CHUNK]
    assert _run(files["obj"], files["npy"], "-o", out, *args) == 0
    got = np.load(out, mmap_mode="r")
    assert got.dtype.names == ("distance", "point", "face") and got.shape == (N,)
    expected = cloud.read_mesh(files["obj"]).closest_point(files["points"], method="certified")
    for name in got.dtype.names:
        assert np.ascontiguousarray(got[name]).tobytes() == getattr(expected, name).tobytes(), name
    assert _run(files["obj"], files["npy"], "-o", out, "--faces") == 0
    assert np.load(out).dtype.names == ("distance", "face")


def _ply(path, points):
    """A binary PLY file of ``points`` with double-precision coordinates."""
    header = f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\n"
    header += "".join(f"property double {axis}\n" for axis in "xyz") + "end_header\n"
    path.write_bytes(header.encode() + np.ascontiguousarray(points, "<f8").tobytes())


def test_ply_points(files, tmp_path):
    finite = files["points"][np.isfinite(files["points"]).all(axis=1)][:5000]
    ply, single = tmp_path / "points.ply", tmp_path / "single.ply"
    _ply(ply, finite)
    trimesh.PointCloud(finite).export(single)  # float coordinates
    assert cloud.Points(ply)[:].tobytes() == finite.tobytes()  # read back exactly
    assert cloud.Points(single)[:].tobytes() == finite.astype(np.float32).astype(np.float64).tobytes()
    for path in (ply, single):
        out = tmp_path / "d.npy"
        assert _run(files["stl"], path, "-o", out, "--chunk", "999") == 0
        expected = _expected(files["stl"], cloud.Points(path)[:]).distance
        assert np.load(out).tobytes() == expected.tobytes()


def test_zarr_points_in_and_zarr_arrays_out(files, tmp_path):
    zarr = pytest.importorskip("zarr")
    source = tmp_path / "points.zarr"
    z = zarr.open_array(str(source), mode="w", shape=(N, 3), chunks=(4096, 3), dtype="f8")
    z[:] = files["points"]
    out = tmp_path / "d.zarr"
    assert _run(files["ply"], source, "-o", out, "--faces", "--closest-points", "--chunk", CHUNK) == 0
    group = zarr.open_group(str(out), mode="r")
    expected = _expected(files["ply"], files["points"])
    assert sorted(group.array_keys()) == ["distance", "face", "point"]
    for name in ("distance", "point", "face"):
        assert group[name].chunks[0] == int(CHUNK)
        assert group[name][:].tobytes() == getattr(expected, name).tobytes(), name


def test_a_dask_cluster_at_an_address_writes_the_same_bits(files, tmp_path, dask_client):
    out, summary = tmp_path / "d.npy", tmp_path / "summary.json"
    address = dask_client.scheduler.address
    args = ["--scheduler", address, "--chunk", CHUNK, "--faces", "--summary", summary]
    assert _run(files["stl"], files["npy"], "-o", out, *args) == 0
    expected = _expected(files["stl"], files["points"])
    got = np.load(out)
    assert got["distance"].tobytes() == expected.distance.tobytes()
    assert got["face"].tobytes() == expected.face.tobytes()
    report = json.loads(summary.read_text())
    assert report["points"] == N and report["nan_rows"] == 3 and report["where"] == address
    assert _run(files["stl"], files["npy"], "-o", out, "--scheduler", address, "--signed") == 0
    signed = cloud.read_mesh(files["stl"], merge=True).signed_distance(files["points"])
    assert np.load(out).tobytes() == signed.tobytes()


def test_workers_start_a_local_cluster_and_report_their_peak_memory(files, tmp_path):
    out, summary = tmp_path / "d.zarr", tmp_path / "summary.json"
    pytest.importorskip("zarr")
    args = ["--workers", "2", "--chunk", CHUNK, "--summary", summary]
    assert _run(files["stl"], files["npy"], "-o", out, *args) == 0
    import zarr

    expected = _expected(files["stl"], files["points"]).distance
    assert zarr.open_group(str(out), mode="r")["distance"][:].tobytes() == expected.tobytes()
    peaks = json.loads(summary.read_text())["peak_rss_bytes"]
    assert len(peaks["workers"]) == 2 and all(p > 0 for p in peaks["workers"].values())


def test_progress_on_a_terminal_is_a_bar(files, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "d.npy") == 0
    err = capsys.readouterr().err
    assert "proximity.cloud" in err and "20.0k/20.0k" in err


def test_progress_on_a_terminal_without_tqdm_is_a_line(files, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "d.npy", "--chunk", CHUNK) == 0
    err = capsys.readouterr().err
    assert "\rproximity.cloud: 20,000/20,000 points (100%," in err


def test_progress_in_a_log_is_plain_lines(files, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(cloud, "LOG_EVERY", 0.0)  # a line per chunk
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "d.npy", "--chunk", CHUNK) == 0
    lines = capsys.readouterr().err.splitlines()
    progress = [line for line in lines if " points (" in line]
    assert len(progress) == 7 and not any("\r" in line for line in lines)
    assert progress[0].startswith("proximity.cloud: 3,000/20,000 points (15%, ") and " left)" in progress[0]
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "d.npy", "--no-progress") == 0
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2 and lines[0].startswith("proximity.cloud: wrote distances of 20,000 points")


def test_signed_distances(files, tmp_path, capsys):
    out = tmp_path / "s.npy"
    assert _run(files["stl"], files["npy"], "-o", out, "--signed", "--faces", "--chunk", CHUNK) == 0
    got = np.load(out)
    mesh = cloud.read_mesh(files["stl"], merge=True)
    assert got.dtype.names == ("signed_distance", "face")
    expected = mesh.signed_distance(files["points"])
    assert got["signed_distance"].tobytes() == expected.tobytes()
    assert (got["signed_distance"] < 0).any() and (got["signed_distance"] > 0).any()
    # The merged mesh is the same surface: the same faces at the same distances.
    np.testing.assert_array_equal(got["face"], _expected(files["stl"], files["points"]).face)
    assert "wrote signed distances, nearest faces of 20,000 points" in capsys.readouterr().err
    # An open mesh: refused with the pseudonormal, answered by the winding number.
    sphere = trimesh.load(files["stl"])
    open_mesh = tmp_path / "open.stl"
    trimesh.Trimesh(sphere.vertices, sphere.faces[sphere.triangles_center[:, 2] < 0.5]).export(open_mesh)
    assert _run(open_mesh, files["npy"], "-o", out, "--signed") == 2
    err = capsys.readouterr().err
    assert "needs a closed mesh" in err and "pass --sign winding" in err
    assert _run(open_mesh, files["npy"], "-o", out, "--sign", "winding") == 0
    expected = cloud.read_mesh(open_mesh, merge=True).signed_distance(files["points"], sign="winding")
    assert np.load(out).tobytes() == expected.tobytes()


def test_the_help_names_the_sign_the_command_uses_by_default(files, tmp_path, capsys):
    with pytest.raises(SystemExit):
        cloud.parser().parse_args(["--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    sign_help = help_text[help_text.index("--sign {") : help_text.index("--closest-points also")]
    stated = __import__("re").findall(r"(\w+) \((?:the )?default", sign_help)
    assert len(stated) == 1, sign_help
    # What --signed does without --sign, as the last line says...
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "d.npy", "--signed", "--no-progress") == 0
    (wrote,) = [line for line in capsys.readouterr().err.splitlines() if " wrote " in line]
    assert wrote.endswith(f"sign {stated[0]})"), wrote
    # ...and TriangleMesh.signed_distance's own default.
    mesh = cloud.read_mesh(files["stl"], merge=True)
    expected = mesh.signed_distance(files["points"], sign=stated[0])
    assert np.load(tmp_path / "d.npy").tobytes() == mesh.signed_distance(files["points"]).tobytes()
    assert np.load(tmp_path / "d.npy").tobytes() == expected.tobytes()


@pytest.fixture(scope="module")
def crossing(tmp_path_factory):
    """Two overlapping spheres in one STL file: a closed mesh that does not bound a solid."""
    sphere = trimesh.creation.icosphere(subdivisions=2)
    path = tmp_path_factory.mktemp("crossing") / "crossing.stl"
    trimesh.util.concatenate([sphere, sphere.copy().apply_translation([0.5, 0, 0])]).export(path)
    return path


def _assert_one_warning_line(err):
    lines = err.splitlines()
    warned = [line for line in lines if line.startswith("proximity.cloud: warning: this mesh does not bound")]
    assert warned and warned[0].endswith("sign='auto' or 'winding' are right"), err
    # Not Python's form: no category, no file and line of proximity's, no source line.
    python = ("RuntimeWarning", "warnings.warn", ".py:")
    assert not any(word in line for line in lines for word in python), err


def test_warnings_are_one_line_messages_of_the_command(files, crossing, tmp_path, capsys):
    out = tmp_path / "d.npy"
    assert _run(crossing, files["npy"], "-o", out, "--sign", "pseudonormal", "--no-progress") == 0
    _assert_one_warning_line(capsys.readouterr().err)


def test_warnings_of_the_commands_own_workers_are_one_line_messages(files, crossing, tmp_path, capfd):
    out = tmp_path / "d.npy"
    args = ("--sign", "pseudonormal", "--no-progress", "--workers", "1")
    assert _run(crossing, files["npy"], "-o", out, *args) == 0
    _assert_one_warning_line(capfd.readouterr().err)  # the worker's stderr is the command's


def test_an_unreadable_stl_is_named_with_trimeshs_reason(tmp_path, files, capsys, monkeypatch):
    # Neither a binary STL (its header counts faces the file does not hold) nor text:
    # trimesh tries both, then a text decoder it may not have, which is not the reason.
    junk = tmp_path / "junk.stl"
    junk.write_bytes(bytes(range(128, 256)) * 3)
    monkeypatch.setitem(sys.modules, "charset_normalizer", None)  # as where it is not installed
    assert _run(junk, files["npy"], "-o", tmp_path / "d.npy") == 2
    err = capsys.readouterr().err
    assert err.startswith(f"proximity.cloud: error: cannot read MESH {str(junk)!r} as a mesh (trimesh: ")
    assert "Binary STL has incorrect length in header" in err and "UnicodeDecodeError" in err
    assert "charset_normalizer" not in err and "ImportError" not in err


# --- Bad input ----------------------------------------------------------------------------------


def _bad(tmp_path, files):
    junk = tmp_path / "junk.stl"
    junk.write_bytes(bytes(range(256)) * 20)
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing\n")
    narrow, words = tmp_path / "narrow.npy", tmp_path / "words.npy"
    np.save(narrow, np.zeros((10, 2)))
    np.save(words, np.array([["a", "b", "c"]]))
    return {
        "missing mesh": ((tmp_path / "no.stl", files["npy"]), "MESH '.*no.stl' does not exist"),
        "unreadable mesh": (
            (junk, files["npy"]),
            # As trimesh reads it: unreadable, or text that holds no face.
            "cannot read MESH '.*junk.stl' as a mesh|MESH '.*junk.stl' holds no faces",
        ),
        "no faces": ((empty, files["npy"]), "MESH '.*empty.obj' holds no faces"),
        "points as mesh": ((files["npy"], files["npy"]), "cannot read MESH '.*points.npy' as a mesh"),
        "missing points": ((files["stl"], tmp_path / "no.npy"), "POINTS '.*no.npy' does not exist"),
        "wrong width": (
            (files["stl"], narrow),
            r"POINTS .*narrow.npy. must have shape \(N, 3\); got shape \(10, 2\)",
        ),
        "not numbers": ((files["stl"], words), "POINTS '.*words.npy' must hold numbers; got dtype <U1"),
        "unknown points": (
            (files["stl"], junk),
            "POINTS '.*junk.stl': expected a .npy or .ply file or a zarr",
        ),
    }


@pytest.mark.parametrize(
    "case",
    ["missing mesh", "unreadable mesh", "no faces", "points as mesh", "missing points", "wrong width",
     "not numbers", "unknown points"],
)  # fmt: skip
def test_bad_input_is_named_and_writes_nothing(files, tmp_path, capsys, case):
    (mesh, points), message = _bad(tmp_path, files)[case]
    out = tmp_path / "d.npy"
    assert _run(mesh, points, "-o", out) == 2
    err = capsys.readouterr().err
    assert err.startswith("proximity.cloud: error: ")
    assert __import__("re").search(message, err), err
    assert not out.exists() and not (tmp_path / "d.npy.partial").exists()


def test_bad_output_and_options(files, tmp_path, capsys):
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "d.txt") == 2
    assert "OUT '" in capsys.readouterr().err
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "no" / "d.npy") == 2
    assert "does not exist" in capsys.readouterr().err
    for args in (["--chunk", "0"], ["--workers", "0"], ["--workers", "2", "--scheduler", "x"]):
        with pytest.raises(SystemExit) as stop:
            _run(files["stl"], files["npy"], "-o", tmp_path / "d.npy", *args)
        assert stop.value.code == 2


# --- Damaged input, an input as OUT, outputs that cannot be written ------------------------------


def _ascii_ply(path, rows, declared):
    header = f"ply\nformat ascii 1.0\nelement vertex {declared}\n"
    header += "".join(f"property double {axis}\n" for axis in "xyz") + "end_header\n"
    path.write_text(header + "".join(" ".join(repr(float(x)) for x in row) + "\n" for row in rows))


def test_an_ascii_ply_that_ends_early_is_refused(files, tmp_path, capsys):
    rows = files["points"][:4]  # finite
    whole, cut = tmp_path / "whole.ply", tmp_path / "cut.ply"
    _ascii_ply(whole, rows, 4)
    _ascii_ply(cut, rows[:3], 4)  # the header's count, but a row short
    out = tmp_path / "d.npy"
    assert _run(files["stl"], whole, "-o", out) == 0
    assert np.load(out).tobytes() == _expected(files["stl"], rows).distance.tobytes()
    out.unlink()
    capsys.readouterr()
    assert _run(files["stl"], cut, "-o", out) == 2
    assert capsys.readouterr().err == (
        f"proximity.cloud: error: POINTS {str(cut)!r} declares 4 vertices but holds 3 (a truncated file?)\n"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.ply", "whole.ply"]


def test_missing_zarr_chunks_are_named(files, tmp_path, capsys):
    zarr = pytest.importorskip("zarr")
    source = tmp_path / "points.zarr"
    z = zarr.open_array(str(source), mode="w", shape=(N, 3), chunks=(4096, 3), dtype="f8")
    z[:] = files["points"]
    (source / z.metadata.encode_chunk_key((1, 0))).unlink()  # rows 4096 to 8191, as a copy cut short
    out = tmp_path / "d.npy"
    assert _run(files["stl"], source, "-o", out) == 0
    assert capsys.readouterr().err.splitlines()[0] == (
        f"proximity.cloud: warning: 1 of 5 chunks of POINTS {str(source)!r} are missing from its store: "
        "their rows read as its fill value (0.0)"
    )
    read = files["points"].copy()
    read[4096:8192] = 0.0
    assert np.load(out).tobytes() == _expected(files["stl"], read).distance.tobytes()


def test_an_out_that_is_an_input_is_refused_and_the_input_kept(files, tmp_path, capsys):
    points = tmp_path / "p.npy"
    np.save(points, files["points"])
    original = points.read_bytes()
    (tmp_path / "link.npy").symlink_to(points)
    os.link(points, tmp_path / "hard.npy")
    (tmp_path / "here").symlink_to(tmp_path, target_is_directory=True)
    group = tmp_path / "group.zarr"
    group.mkdir()
    np.save(group / "q.npy", files["points"])
    names = sorted(p.name for p in tmp_path.iterdir())
    cases = [  # (POINTS, OUT, other arguments)
        ("p.npy", "p.npy", []),  # the same name
        ("p.npy", "link.npy", []),  # a symbolic link to POINTS
        ("link.npy", "p.npy", []),  # POINTS a link to OUT
        ("p.npy", "hard.npy", []),  # a hard link
        ("p.npy", "here/p.npy", []),  # through a linked directory
        ("group.zarr/q.npy", "group.zarr", []),  # a directory that holds POINTS
        ("p.npy", "d.npy", ["--summary", tmp_path / "here" / "p.npy"]),
    ]
    for source, out, more in cases:
        assert _run(files["stl"], tmp_path / source, "-o", tmp_path / out, *more) == 2, (source, out)
        err = capsys.readouterr().err
        clash = "holds" if out == "group.zarr" else "is"
        what = "" if out == "group.zarr" else " (the same file)"
        assert err.startswith("proximity.cloud: error: ") and err.endswith(
            f"{clash} POINTS {str(tmp_path / source)!r}{what}: writing it would replace the input\n"
        ), err
        assert points.read_bytes() == original
        assert sorted(p.name for p in tmp_path.iterdir()) == names


def test_an_input_as_out_s_partial_file_is_refused(files, tmp_path, capsys):
    zarr = pytest.importorskip("zarr")
    source = tmp_path / "d.npy.partial"  # a zarr array, which OUT d.npy would remove
    zarr.open_array(str(source), mode="w", shape=(N, 3), chunks=(4096, 3), dtype="f8")[:] = files["points"]
    assert _run(files["stl"], source, "-o", tmp_path / "d.npy") == 2
    assert "OUT's partial file" in capsys.readouterr().err
    assert zarr.open_array(str(source), mode="r")[:].tobytes() == files["points"].tobytes()


def _listing(directory):
    return sorted(p.name for p in directory.iterdir())


def test_an_out_that_is_a_directory(files, tmp_path, capsys):
    (tmp_path / "d.npy").mkdir()
    assert _run(files["stl"], files["npy"], "-o", tmp_path / "d.npy") == 2
    assert (
        capsys.readouterr().err == f"proximity.cloud: error: OUT {str(tmp_path / 'd.npy')!r} is a directory\n"
    )
    assert _listing(tmp_path) == ["d.npy"] and _listing(tmp_path / "d.npy") == []


def test_a_read_only_directory(files, tmp_path, tmpfs, capsys):
    if os.geteuid() == 0:  # root writes through permissions: a read-only filesystem
        directory = tmpfs(1 << 20, read_only=True)
    else:
        directory = tmp_path / "read-only"
        directory.mkdir(mode=0o555)
    for name in ("d.npy", "d.zarr"):
        assert _run(files["stl"], files["npy"], "-o", directory / name) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"proximity.cloud: error: cannot write OUT {str(directory / name)!r}: "), err
        assert err.count("\n") == 1
        assert _listing(directory) == []


@pytest.mark.parametrize("out", ["d.npy", "r.npy", "d.zarr"])
def test_a_full_disk(files, tmpfs, capsys, out):
    disk = tmpfs(256 << 10, free=0)
    args = ["--closest-points", "--faces"] if out == "r.npy" else []  # records
    assert _run(files["stl"], files["npy"], "-o", disk / out, *args) == 2
    assert capsys.readouterr().err == (
        f"proximity.cloud: error: cannot write OUT {str(disk / out)!r}: No space left on device\n"
    )
    assert _listing(disk) == ["filler0"]


@pytest.mark.parametrize("out, allocate", [("d.npy", True), ("d.npy", False), ("d.zarr", False)])
def test_a_disk_too_small_for_the_output(files, tmpfs, out, allocate):
    """Room for about a third of the distances: an ``.npy`` output is
    allocated up front and fails before the queries; without the allocation
    (a filesystem that does not support it) or as zarr chunks, the write of
    a later chunk fails.  In a new process: a write through a memory map
    kills it (SIGBUS)."""
    disk = tmpfs(1 << 20, free=N * 8 // 3)
    code = textwrap.dedent(
        f"""
        import os, sys
        from proximity import cloud
        if not {allocate} and hasattr(os, "posix_fallocate"):
            del os.posix_fallocate
        query, calls = cloud._query, []
        def counted(*args):
            calls.append(1)
            return query(*args)
        cloud._query = counted
        code = cloud.main({[str(files["stl"]), str(files["npy"]), "-o", str(disk / out), "--chunk", CHUNK]!r})
        print(len(calls))
        sys.exit(code)
        """
    )
    # Quiet: a process that compiles a kernel says so on stderr.
    env = {**os.environ, "PROXIMITY_QUIET": "1"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 2, done.stderr[-2000:]
    assert (
        done.stderr
        == f"proximity.cloud: error: cannot write OUT {str(disk / out)!r}: No space left on device\n"
    )
    assert _listing(disk) == ["filler0"]
    calls = int(done.stdout)
    if allocate and hasattr(os, "posix_fallocate"):
        assert calls == 0
    else:
        assert 1 < calls < N // int(CHUNK) + 1


# --- A job that stops midway ---------------------------------------------------------------------


def test_an_interrupted_job_leaves_the_previous_output_and_no_partial(files, tmp_path, monkeypatch, capsys):
    out = tmp_path / "d.npy"
    np.save(out, np.arange(3.0))  # a previous run's complete output
    query, calls = cloud._query, []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return query(*args)

    monkeypatch.setattr(cloud, "_query", interrupted)
    assert _run(files["stl"], files["npy"], "-o", out, "--chunk", CHUNK) == 130
    assert "interrupted; no output written" in capsys.readouterr().err
    assert np.load(out).tolist() == [0.0, 1.0, 2.0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.npy"]


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL])
def test_a_job_stopped_by_a_signal_leaves_no_complete_looking_output(files, tmp_path, signum):
    # The process signals itself in the middle of the third chunk.
    out = tmp_path / "d.npy"
    code = textwrap.dedent(
        f"""
        import os, sys
        from proximity import cloud
        query, calls = cloud._query, []
        def stopped(*args):
            calls.append(1)
            if len(calls) == 3:
                os.kill(os.getpid(), {int(signum)})
            return query(*args)
        cloud._query = stopped
        args = [{str(files["stl"])!r}, {str(files["npy"])!r}, "-o", {str(out)!r}, "--chunk", "3000"]
        sys.exit(cloud.main(args))
        """
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    names = sorted(p.name for p in tmp_path.iterdir())
    if signum == signal.SIGTERM:
        assert done.returncode == 128 + signum, done.stderr[-2000:]
        assert names == []
    else:
        assert done.returncode == -signum
        assert names == ["d.npy.partial"]  # never renamed: not mistaken for a result


def test_the_module_runs_as_a_command(files, tmp_path):
    out = tmp_path / "d.npy"
    done = subprocess.run(
        [sys.executable, "-m", "proximity.cloud", str(files["stl"]), str(files["npy"]), "-o", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert "3 of 20,000 rows" in done.stderr
    assert np.load(out).tobytes() == _expected(files["stl"], files["points"]).distance.tobytes()
