import os
import sys

# Tests run against the source tree; importing styletrace selects the JIT variant and libLLVM.
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "src"))
sys.path.insert(0, os.path.dirname(__file__))
