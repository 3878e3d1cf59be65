"""``python -m masonry_dem.cli``: the command line (same as ``masonry-dem``)."""

import sys

from masonry_dem.cli import main

sys.exit(main())
