import pytest

import styletrace

styletrace.init()  # the denoising tests render: pick the backend and register the plugins first

pyoidn = pytest.importorskip("pyoidn", reason="the 'denoise' extra (pyoidn) is not installed")
