"""What each observed atom is when nothing is broken, as the model entails it (PySAT).

The page colours an observation by health, not by truth: ``tripped(hokuyo) = false`` is
healthy, ``on(hokuyo) = false`` is not. Which value is healthy follows from the model: the
value every model of the theory with no component abnormal gives the atom.
"""

from __future__ import annotations

from host.diagnosis import generate, load_system
from host.diagnosis.healthy import healthy_values
from host.diagnosis.logic import Clause, Literal, Theory, ab, horn, nab
from tests.daemon.runner import TEDUSAR


def test_the_tedusar_model_says_which_value_of_each_atom_is_healthy() -> None:
    values = healthy_values(generate(load_system(TEDUSAR)))
    assert values["tripped(hokuyo)"] is False
    assert values["on(hokuyo)"] is True
    assert values["in_band(jaguar)"] is True  # healthy and powered: in its band
    assert values["ok(/scan)"] is True
    assert values["ok(/map)"] is True  # through ok(/scan): a chain of rules
    assert values["running(rviz)"] is True
    assert values["link(board)"] is True
    assert values["matched(odom_yaw_rate,imu_yaw_rate)"] is True
    # a trend is neither healthy nor not: the model leaves it free
    assert "inc(odom_yaw_rate)" not in values and "const(imu_yaw_rate)" not in values
    assert not any(a.startswith("AB(") for a in values)


def test_free_atoms_and_a_model_that_contradicts_itself_give_no_expectation() -> None:
    t = Theory(("a",), (horn([nab("a")], [Literal("p")]),
                        Clause((Literal("q"), Literal("r")))))
    assert healthy_values(t) == {"p": True}
    assert healthy_values(t, ["p", "q", "unknown_atom"]) == {"p": True}
    broken = Theory(("a",), (horn([nab("a")], [Literal("p")]),
                             horn([nab("a")], [Literal("p", False)]),
                             Clause((Literal(ab("a"), False),))))
    assert healthy_values(broken) == {}
