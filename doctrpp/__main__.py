import sys

from doctrpp.cli import main

sys.exit(main())
