"""``python -m springchain``: the command line."""

from .cli import main

raise SystemExit(main())
