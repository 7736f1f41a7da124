"""``python -m speckle.synthoct CONFIG.ini SCATTERERS.txt OUTPUT.png`` (= ``speckle-scan``)."""

import sys

from .cli import main

sys.exit(main())
