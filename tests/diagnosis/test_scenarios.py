"""The papers' scenarios on the tedusar model (paper 000 §VI), with both search algorithms."""

from __future__ import annotations

import pytest

from host.diagnosis import ALGORITHMS, ComponentKind, Theory, load_system
from tests.diagnosis.conftest import TEDUSAR, diagnoser_for

# paper 000 §VI-A: Δbad = {j, h, la, lan, lac, hm, jn, hn, in, jtn, jyn}
PAPER_POWER_UP_BAD = {
    "jaguar", "hokuyo", "laser_alignment", "laser_alignment_node", "laser_alignment_control",
    "hector_mapping", "jaguar_node", "hokuyo_node", "imu_node", "jaguar_teleop_node", "joy_node",
}
# the robot's model goes beyond the paper's: the missions' thermal camera and its driver, which
# the paper's power-up observations (power-up.obs) say nothing of
BEYOND_PAPER = {"thermal_camera", "thermal_camera_node"}


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_power_up_every_device_and_node_abnormal(tedusar: Theory, algorithm: str) -> None:
    d = diagnoser_for(tedusar, "power-up", algorithm)
    result = d.diagnose()
    assert result.complete and result.explainable
    assert result.bad_sets() == [frozenset(PAPER_POWER_UP_BAD)]
    model = load_system(TEDUSAR)
    observed_nodes = {c.name for c in model.by_kind(
        ComponentKind.N, ComponentKind.HN, ComponentKind.SN)} - {"rviz"}
    switchable = {c.name for c in model.by_kind(ComponentKind.SH)}
    assert observed_nodes | switchable == PAPER_POWER_UP_BAD | BEYOND_PAPER
    assert result.diagnoses[0].good == {"imu", "joystick", "rviz", "board"} | BEYOND_PAPER


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_device_shut_down_blames_jaguar(tedusar: Theory, algorithm: str) -> None:
    d = diagnoser_for(tedusar, "device-shut-down", algorithm)
    result = d.diagnose()
    assert result.complete
    assert result.bad_sets() == [frozenset({"jaguar"})]


def test_after_power_up_of_jaguar_the_hung_driver_is_blamed(tedusar: Theory) -> None:
    # §VI-B, second planner call: jaguar is powered again but jaguar_node still publishes
    # no odometry, so the driver (or, equally small, the base itself) is suspected.
    d = diagnoser_for(tedusar, "device-shut-down")
    d.observe("on(jaguar)")
    d.observe("in_band(jaguar)")
    assert set(d.diagnose().bad_sets()) == {frozenset({"jaguar_node"}), frozenset({"jaguar"})}
    d.observe("running(jaguar_node)")
    d.observe("~matched(odom_yaw_rate,imu_yaw_rate)")
    # the trend mismatch implicates jaguar_node or imu_node; only jaguar_node explains both
    assert d.diagnose().bad_sets()[0] == frozenset({"jaguar_node"})


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_double_fault(tedusar: Theory, algorithm: str) -> None:
    d = diagnoser_for(tedusar, "device-shut-down", algorithm)
    d.observe("~running(hector_mapping)")
    d.observe("~ok(/map)")
    result = d.diagnose()
    assert result.bad_sets() == [frozenset({"jaguar", "hector_mapping"})]
    assert result.diagnoses[0].cardinality == 2


def test_double_fault_with_alternatives_ranked_by_prior(tedusar: Theory) -> None:
    d = diagnoser_for(tedusar, "device-shut-down")
    d.observe("~ok(/scan)")  # hokuyo (prior 0.02) or hokuyo_node (default 0.01)
    d.observe("~ok(/map)")
    result = d.diagnose()
    assert result.bad_sets() == [
        frozenset({"jaguar", "hokuyo"}),
        frozenset({"jaguar", "hokuyo_node"}),
    ]
    assert result.diagnoses[0].probability > result.diagnoses[1].probability
    assert abs(sum(x.probability for x in result.diagnoses) - 1.0) < 1e-9


def test_board_observations(tedusar: Theory) -> None:
    d = diagnoser_for(tedusar, "device-shut-down")
    d.observe("on(jaguar)")
    d.observe("ok(/odom)")
    assert d.diagnose().bad_sets() == [frozenset()]
    d.observe("tripped(hokuyo)")  # a tripped channel is not a healthy one
    assert d.diagnose().bad_sets() == [frozenset({"hokuyo"})]
    d.retract("tripped(hokuyo)")
    d.observe("~in_band(laser_alignment)")  # powered but drawing current out of its band
    assert d.diagnose().bad_sets() == [frozenset({"laser_alignment"})]


def test_a_lost_board_link_blames_the_link_not_the_devices(tedusar: Theory) -> None:
    # The robot runs; then the board stops answering. The hardware observer retracts what
    # it can no longer see (on, in_band, tripped become unknown) and reports ~link(board).
    d = diagnoser_for(tedusar, "device-shut-down")
    d.observe("on(jaguar)")
    d.observe("ok(/odom)")
    for device in ("jaguar", "hokuyo", "laser_alignment"):
        for atom in (f"on({device})", f"in_band({device})", f"tripped({device})"):
            d.retract(atom)
    d.observe("~link(board)")
    result = d.diagnose()
    assert result.bad_sets() == [frozenset({"board"})]
