"""Attempts counted as a person counts them (issue: three successful repairs of the base must
not quarantine it at the next fault; a fault that comes back at once after a repair counts)."""

from __future__ import annotations

from host.repair.limits import AttemptLimiter


def test_the_bring_up_never_counts() -> None:
    lim = AttemptLimiter(3, 600.0, stable_s=60.0)
    lim.record("jaguar", 0.0)  # the power-up of the robot
    lim.verified("jaguar", 5.0)
    assert lim.count("jaguar", 5.0) == 0
    lim.record("jaguar", 10.0)  # a fault soon after: the first real repair
    assert lim.count("jaguar", 10.0) == 1


def test_repairs_that_held_do_not_add_up_to_a_quarantine() -> None:
    lim = AttemptLimiter(3, 600.0, stable_s=60.0)
    lim.record("jaguar", 0.0)
    lim.verified("jaguar", 1.0)  # bring-up
    for k in range(3):  # three faults, each repaired and holding for over a minute
        t = 100.0 + 100.0 * k
        lim.record("jaguar", t)
        lim.verified("jaguar", t + 2.0)
    assert not lim.exhausted("jaguar", 400.0)
    assert lim.count("jaguar", 400.0) == 0
    lim.record("jaguar", 400.0)  # the fourth fault gets its try
    assert lim.count("jaguar", 400.0) == 1


def test_a_repair_that_flaps_counts() -> None:
    lim = AttemptLimiter(3, 600.0, stable_s=60.0)
    lim.record("hokuyo", 0.0)
    lim.verified("hokuyo", 1.0)  # bring-up
    for k in range(3):  # it drops out again 10 s after every verified repair
        t = 10.0 + 12.0 * k
        lim.record("hokuyo", t)
        lim.verified("hokuyo", t + 2.0)
    assert lim.count("hokuyo", 45.0) == 3  # each repair was followed by a new fault
    assert lim.exhausted("hokuyo", 45.0)
    # the last one, if nothing follows it for a minute, held; the two that flapped stay
    assert lim.count("hokuyo", 200.0) == 2


def test_failed_attempts_count_until_the_window_ends() -> None:
    lim = AttemptLimiter(3, 600.0, stable_s=60.0)
    for t in (0.0, 10.0, 20.0):
        lim.record("laser_alignment", t)  # never verified
    assert lim.exhausted("laser_alignment", 30.0)
    assert lim.count("laser_alignment", 605.0) == 2
    assert lim.count("laser_alignment", 621.0) == 0


def test_reset_forgets_everything_but_the_bring_up() -> None:
    lim = AttemptLimiter(2, 600.0)
    lim.record("a", 0.0)
    lim.verified("a", 1.0)
    lim.record("a", 2.0)
    lim.record("a", 3.0)
    assert lim.exhausted("a", 3.0)
    lim.reset("a")
    assert lim.count("a", 3.0) == 0
    lim.record("a", 4.0)
    lim.verified("a", 5.0)  # not a bring-up any more: it counts until it held
    assert lim.count("a", 6.0) == 1


def test_bring_ups_after_board_reboots_never_count() -> None:
    """Issue 11, item 5: brown-outs 30 s apart quarantined the base, the lidar and the leveling
    mount — each reboot's bring-up counted as a flapping repair of every device."""
    lim = AttemptLimiter(3, 600.0, stable_s=60.0)
    lim.record("jaguar", 0.0)
    lim.verified("jaguar", 5.0)  # the robot's power-up
    for k in range(6):  # the board reboots every 30 s; every device is brought up again
        t = 30.0 * (k + 1)
        lim.board_rebooted()
        lim.record("jaguar", t + 1.0)
        lim.verified("jaguar", t + 6.0)
    assert lim.count("jaguar", 200.0) == 0 and not lim.exhausted("jaguar", 200.0)
    lim.record("jaguar", 205.0)  # a fault of the device itself, 5 s after its bring-up
    assert lim.count("jaguar", 205.0) == 1  # counts, but the bring-ups did not


def test_a_failed_attempt_before_the_reboot_still_counts() -> None:
    lim = AttemptLimiter(3, 600.0, stable_s=60.0)
    lim.record("hokuyo", 0.0)
    lim.verified("hokuyo", 5.0)
    lim.record("hokuyo", 10.0)  # a repair that never worked
    lim.board_rebooted()
    assert lim.count("hokuyo", 20.0) == 1
