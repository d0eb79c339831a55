import sys

from roomba_bt.cli import main

sys.exit(main())
