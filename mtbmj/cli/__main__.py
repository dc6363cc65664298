"""``python -m mtbmj.cli ...`` runs the ``mtbmj`` command."""
import sys

from mtbmj.cli import main

sys.exit(main())
