"""The corpus tests render: pick the backend and register styletrace's plugins (`styled`) before
any scene loads."""
import styletrace

styletrace.init()
