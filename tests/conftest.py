"""The test session is an entry point like the command line: the compiled kernels' threads
wait passively between parallel loops (see :func:`masonry_dem.set_thread_wait_policy`)."""

import masonry_dem

masonry_dem.set_thread_wait_policy()
