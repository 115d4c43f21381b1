"""The hostile-input corpus renders and builds styles: pick the backend and register the plugins
first."""
import styletrace

styletrace.init()
