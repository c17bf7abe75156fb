"""``python -m camlog``: the command line."""

import sys

from camlog.cli import main

sys.exit(main())
