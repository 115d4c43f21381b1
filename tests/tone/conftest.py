import styletrace

styletrace.init()  # these tests render: pick the backend and register the plugins first
