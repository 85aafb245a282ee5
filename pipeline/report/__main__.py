"""``python -m pipeline.report``: run the report stage (see :mod:`pipeline.report`)."""

import sys

from pipeline.report.build import main

sys.exit(main())
