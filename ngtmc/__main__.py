"""``python -m ngtmc ...`` is the ``ngtmc`` command line (see :mod:`ngtmc.cli`)."""
import sys

from .cli import main

sys.exit(main())
