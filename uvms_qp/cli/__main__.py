"""``python -m uvms_qp.cli`` runs the command line (as ``uvms-qp`` and ``python -m uvms_qp``)."""

import sys

from . import main

sys.exit(main())
