"""``python -m mtbmj.cli ...`` runs the ``mtbmj`` command."""
import sys

from mtbmj.cli._entry import main

sys.exit(main())
