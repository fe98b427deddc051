"""``python -m ngtmc.report RUN_DIR ...``: see :func:`ngtmc.report.command.report_main`."""
import sys

from ngtmc.report.command import report_main

sys.exit(report_main())
