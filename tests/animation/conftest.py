import styletrace

styletrace.init()  # the pipeline's tests resolve jobs: pick the backend, register the plugins first
