"""python -m pcr.plot DIR: the figures of a `pcr demo` output directory (see pcr.plot._demo)."""
import sys

from ._demo import main

sys.exit(main())
