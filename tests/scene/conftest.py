import styletrace

# the scene-analysis tests render: pick the backend and register the plugins first
styletrace.init()
