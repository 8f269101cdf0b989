"""python -m pcr.study: the same as the pcr-study command."""
import sys

from .._study_cli import main

sys.exit(main())
