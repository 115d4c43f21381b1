"""Style tests run inside Dr.Jit kernels: pick the backend and register the plugins first."""
import styletrace

styletrace.init()
