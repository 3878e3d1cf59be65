"""The test session is an entry point like the command line: the compiled kernels' threads
wait passively between parallel loops (see :func:`masonry_dem.set_thread_wait_policy`)."""

import pytest

import masonry_dem

masonry_dem.set_thread_wait_policy()


@pytest.hookimpl(tryfirst=True)  # before the -m option deselects by marker
def pytest_collection_modifyitems(items):
    """The ParaView tests (pvbatch under xvfb-run, about 70 s together) belong to the slow
    tier, which CI runs after the default one (``-m slow``)."""
    for item in items:
        if item.get_closest_marker("paraview") is not None:
            item.add_marker(pytest.mark.slow)
