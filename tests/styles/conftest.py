"""Style tests: importing styletrace selects a JIT variant (llvm_ad_rgb on this machine)."""
import styletrace  # noqa: F401  (sets the Mitsuba variant before the style modules are used)
