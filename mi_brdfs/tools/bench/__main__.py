"""``python -m mi_brdfs.tools.bench --worker TASK OPTIONS_JSON``: one measurement
in a process of its own (see workers.py); the bench itself is ``mi-brdfs bench``."""
import sys

from .workers import main

if len(sys.argv) == 4 and sys.argv[1] == "--worker":
    sys.exit(main(sys.argv[2], sys.argv[3]))
sys.exit("usage: python -m mi_brdfs.tools.bench --worker TASK OPTIONS_JSON (else: mi-brdfs bench)")
