"""``python -m robots``: one robot process."""

import sys

from robots.cli import main

sys.exit(main())
