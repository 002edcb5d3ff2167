"""Fixtures shared by the test modules."""

import pytest


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
