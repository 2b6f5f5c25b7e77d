import pytest

from configs import ConfigError
from qshape import OutlineParams, ToleranceError, Tolerances


def test_bundled_defaults_match_dataclass_defaults():
    assert Tolerances.load() == Tolerances()
    assert OutlineParams.load() == OutlineParams()


def test_overrides_and_paths(tmp_path):
    tol = Tolerances.load(color_distance=0.3, right_angle_deg=[80, 100])
    assert tol.color_distance == 0.3
    assert tol.right_angle_deg == (80.0, 100.0)
    path = tmp_path / "t.yaml"
    path.write_text("tolerances:\n  joint_width: 3.0\n")
    assert Tolerances.load(path).joint_width == 3.0
    flat = tmp_path / "flat.yaml"
    flat.write_text("joint_width: 1.5\n")
    assert Tolerances.load(flat).joint_width == 1.5


def test_unknown_key_is_an_error():
    with pytest.raises(ConfigError, match="allowed"):
        Tolerances.load(colour_distance=0.3)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"right_angle_deg": (95.0, 85.0)},
        {"right_angle_deg": (85.0,)},
        {"right_angle_deg": (-5.0, 95.0)},
        {"equal_length_ratio": (1.2, 0.8)},
        {"semicircle_ratio": (0.0, 1.1)},
        {"angle_margin_deg": -1.0},
        {"angle_margin_deg": 5.0},  # as wide as half the right-angle band
        {"length_margin": 0.3},
        {"semicircle_margin": 0.12},
        {"color_distance": 0.0},
        {"joint_width": float("nan")},
        {"size_area_threshold": -1.0},
        {"cone_margin_deg": 30.0},
        {"max_key_variants": 0},
    ],
)
def test_invalid_tolerances_raise(kwargs):
    with pytest.raises(ToleranceError):
        Tolerances(**kwargs)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"resample_points": 4},
        {"corner_angle_deg": 0.0},
        {"max_curve_turn_deg": 45.0},
        {"corner_window": 0.0},
        {"merge_fraction": 0.7},
    ],
)
def test_invalid_outline_params_raise(kwargs):
    with pytest.raises(ToleranceError):
        OutlineParams(**kwargs)


def test_tolerance_error_is_a_value_error():
    with pytest.raises(ValueError):
        Tolerances(color_distance=-1.0)
