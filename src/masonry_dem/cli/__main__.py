"""``python -m masonry_dem.cli``: the ``masonry-dem`` command."""

import sys

from masonry_dem.cli import main

sys.exit(main())
