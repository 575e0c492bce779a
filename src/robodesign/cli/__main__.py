import sys

from robodesign.cli.entry import main

sys.exit(main())
