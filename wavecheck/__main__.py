import sys

from wavecheck.cli import main

sys.exit(main())
