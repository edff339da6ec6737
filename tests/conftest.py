import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

# The suite runs with infuse's built-in plugin defaults, whatever the user's configuration file and
# environment choose (tests of the configuration set their own).
os.environ["INFUSE_CONFIG"] = os.devnull
for _name in [n for n in os.environ if n.startswith("INFUSE_DEFAULT_")]:
    del os.environ[_name]
