import sys

from styletrace.frontends.cli import main

sys.exit(main())
