"""``python -m ocgroupoid``: the command line."""

import sys

try:
    from .cli import main
except KeyboardInterrupt:  # pragma: no cover - the guard of ocgroupoid._startup acts first
    sys.stderr.write("ocgroupoid: interrupted while starting\n")
    sys.exit(130)

main()
