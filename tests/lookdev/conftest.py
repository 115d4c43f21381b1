import styletrace

# the look-development tests render: pick the backend and register the plugins first
styletrace.init()
