import styletrace

styletrace.init()  # the schedule renders: pick the backend and register the plugins first
