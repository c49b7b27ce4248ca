import sys

from stepgen.cli import main

sys.exit(main())
