"""Fixtures shared by the test modules."""

import subprocess

import pytest

from tests import disks


@pytest.fixture(scope="session")
def dask_client():
    """A client of a local Dask cluster of two worker processes, one thread
    each; made current only inside the tests that use it."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        with distributed.Client(cluster, set_as_default=False) as client:
            yield client


@pytest.fixture
def tmpfs(tmp_path):
    """``tmpfs(size, free=None, read_only=False)``: the path of a tmpfs of
    ``size`` bytes mounted for the test, with about ``free`` bytes of it left
    free (see :func:`tests.disks.fill`; all of it where None); skips the test
    where none can be mounted (it takes root)."""
    mounts = []

    def mount(size, free=None, read_only=False):
        path = tmp_path / f"tmpfs{len(mounts)}"
        path.mkdir()
        options = f"size={size}" + (",ro" if read_only else "")
        try:
            done = subprocess.run(
                ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)], capture_output=True
            )
            error = done.stderr.decode(errors="replace").strip() if done.returncode else None
        except OSError as exc:
            error = str(exc)
        if error is not None:
            pytest.skip(f"cannot mount a tmpfs here (it takes root): {error[:100]}")
        mounts.append(path)
        if free is not None:
            disks.fill(path, free)
        return path

    yield mount
    for path in mounts:
        subprocess.run(["umount", str(path)], check=True)
