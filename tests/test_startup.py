"""Start-up never fails: read-only installs, and no writable cache at all."""

import os
import pathlib
import shutil
import subprocess
import sys

import proximity

QUERY = (
    "import warnings, numpy as np, proximity; "
    "print(float(proximity.Triangle([[0, 0, 0], [1, 0, 0], [0, 1, 0]]).distance([0.25, 0.25, 2.0])))"
)


def _run(tmp_path, cache_home):
    """Run a query with a copy of the package whose own cache directory cannot be made."""
    package = tmp_path / "site" / "proximity"
    shutil.copytree(
        pathlib.Path(proximity.__file__).parent, package, ignore=shutil.ignore_patterns("__pycache__")
    )
    # A file where the cache directory would go: even root cannot make it, as
    # in a read-only install.
    (package / "__pycache__").write_text("")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(tmp_path / "site"), XDG_CACHE_HOME=str(cache_home), HOME=str(cache_home))
    return subprocess.run(
        [sys.executable, "-c", QUERY], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600
    )


def test_read_only_package_uses_the_user_cache(tmp_path):
    cache_home = tmp_path / "home"
    result = _run(tmp_path, cache_home)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "2.0"
    assert "RuntimeWarning" not in result.stderr
    assert any(p.suffix == ".nbi" for p in cache_home.rglob("*")), "nothing cached in the user cache"


def test_no_writable_cache_warns_and_still_answers(tmp_path):
    blocker = tmp_path / "not-a-directory"
    blocker.write_text("")
    result = _run(tmp_path, blocker / "home")  # under a file: cannot be created
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "2.0"
    assert "no writable cache directory" in result.stderr
