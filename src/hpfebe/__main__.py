"""``python -m hpfebe``: the same as the ``hpfebe`` console script.  Under the workflow's
local job server (``HPFEBE_JOBSERVER`` set, :mod:`hpfebe.jobclient`) the command
runs in a process forked from the server, which has imported everything already; else,
or when the server cannot take it, here."""

import os
import sys

if __name__ == "__main__":
    if os.environ.get("HPFEBE_JOBSERVER"):
        from .jobclient import delegate

        code = delegate(sys.argv[1:])
        if code is not None:
            sys.exit(code)
    from .cli import main

    sys.exit(main())
