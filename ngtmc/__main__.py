"""``python -m ngtmc ...`` is the ``ngtmc`` command line (see :mod:`ngtmc.cli`)."""
import sys

from ngtmc.cli import main

sys.exit(main())
