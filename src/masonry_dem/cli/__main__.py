import sys

from masonry_dem.cli import main

sys.exit(main())
