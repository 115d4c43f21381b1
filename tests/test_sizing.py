"""Pass sizes for the device: flat on the CPU, from the GPU's total memory on CUDA (a fake device
here)."""
from styletrace.frontends import api
from styletrace.pipeline.sizing import CUDA_LANE_BYTES, CUDA_LANES_MAX, lanes_per_pass

GiB = 1 << 30


def test_cpu_keeps_the_flat_pass_size_whatever_memory_there_is():
    assert lanes_per_pass("llvm_ad_rgb", query=lambda: (1000 * GiB, 1000 * GiB)) == (
        api.LANES_PER_PASS,
        None,
    )


def test_cuda_takes_half_the_total_memory_as_a_power_of_two():
    lanes, note = lanes_per_pass("cuda_ad_rgb", query=lambda: (79 * GiB, 80 * GiB))
    assert lanes == 1 << 25 and note is None  # 40 GiB / 1 KiB = 40 Mi lanes -> 32 Mi
    assert 512 * 512 * 256 // lanes == 2  # the H100 benchmark's render: 2 launches instead of 64


def test_cuda_split_ignores_free_memory_that_still_fits():
    """The split decides the samples: a little less free memory must not change the image."""
    a = lanes_per_pass("cuda_ad_rgb", query=lambda: (79 * GiB, 80 * GiB))
    b = lanes_per_pass("cuda_ad_rgb", query=lambda: (33 * GiB, 80 * GiB))
    assert a == b


def test_cuda_halves_when_free_memory_is_short_and_says_so():
    lanes, note = lanes_per_pass("cuda_ad_rgb", query=lambda: (10 * GiB, 80 * GiB))
    assert lanes * CUDA_LANE_BYTES <= 10 * GiB and lanes == 1 << 23
    assert "differs from this device's default split" in note and "--pass-spp" in note


def test_cuda_bounds():
    assert lanes_per_pass("cuda_ad_rgb", query=lambda: None) == (api.LANES_PER_PASS, None)
    assert lanes_per_pass("cuda_ad_rgb", query=lambda: (1 << 50, 1 << 50))[0] == CUDA_LANES_MAX
    assert (
        lanes_per_pass("cuda_ad_rgb", query=lambda: (GiB // 4, GiB // 2))[0] == api.LANES_PER_PASS
    )
