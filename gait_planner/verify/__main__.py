"""``python -m gait_planner.verify RUN.mcap [...]``: print the report of each recording."""

import sys

from gait_planner.verify import main

sys.exit(main())
