import sys

from vehicle_agents.simulator import main

sys.exit(main())
