import styletrace

styletrace.init()  # the look-development tests render: pick the backend and register the plugins first
