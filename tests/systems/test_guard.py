"""The guarded push-in's stop logic on synthetic effort sequences (the Drake runs: tests/systems/test_guarded_drake.py)."""

import numpy as np
import pytest

from slax_drake.systems.guard import ContactMonitor

RNG = np.random.default_rng(0)
PUSH = RNG.normal(size=(50, 9))  # J^T u along a push-in, one row per sample
WEIGHT = RNG.normal(size=(50, 9))  # J^T z


def _run(monitor, residuals):
    forces = []
    for k, r in enumerate(residuals):
        monitor = monitor.update(r, PUSH[k], WEIGHT[k])
        forces.append(monitor.force)
        if monitor.stopped:
            return monitor, k, forces
    return monitor, None, forces


def test_a_carried_weight_never_stops_the_push_however_the_arm_turns():
    residuals = [12.0 * WEIGHT[k] for k in range(50)]  # a 12 N payload, its efforts changing with the pose
    monitor, stop, forces = _run(ContactMonitor(threshold=5.0), residuals)
    assert stop is None
    assert monitor.weight == pytest.approx(12.0)
    assert max(abs(f) for f in forces) < 1e-6


def test_the_push_stops_at_the_first_sample_whose_resisting_force_crosses_the_threshold():
    resisting = np.concatenate([np.zeros(30), np.arange(1, 21) * 1.0])  # N: contact from sample 30, +1 N a sample
    residuals = [3.0 * WEIGHT[k] + resisting[k] * PUSH[k] for k in range(50)]
    monitor, stop, forces = _run(ContactMonitor(threshold=5.0), residuals)
    assert stop == 35  # 6 N > 5 N
    assert monitor.force == pytest.approx(6.0)
    assert all(f <= 5.0 + 1e-9 for f in forces[:-1])


def test_a_force_along_the_push_does_not_stop_it_and_the_expected_drag_raises_the_threshold():
    pulling = [3.0 * WEIGHT[k] - (20.0 if k > 10 else 0.0) * PUSH[k] for k in range(50)]  # helps the push
    assert _run(ContactMonitor(threshold=5.0), pulling)[1] is None
    sliding = [3.0 * WEIGHT[k] + (8.0 if k > 10 else 0.0) * PUSH[k] for k in range(50)]  # 8 N of floor friction
    assert _run(ContactMonitor(threshold=5.0), sliding)[1] == 11
    assert _run(ContactMonitor(threshold=5.0, expected=8.0), sliding)[1] is None


def test_the_carried_payload_s_inertia_is_no_contact():
    """A 1 kg payload (9.81 N fitted at rest) accelerating with the cup: its m a shows in the residual along the
    push; with the payload signature (efforts per kg of cup acceleration) the monitor takes it out, and a contact
    on top still stops the push."""
    accel = np.concatenate([np.zeros(5), np.full(20, 3.0), np.zeros(25)])  # m/s^2 along the push, samples 5-24
    payload = [accel[k] * PUSH[k] for k in range(50)]  # J^T a_cup, the cup accelerating along u
    residuals = [9.81 * WEIGHT[k] + 1.0 * payload[k] for k in range(50)]  # 1 kg x 3 m/s^2 = 3 N along the push
    assert _run(ContactMonitor(threshold=2.0), residuals)[1] == 5  # read as a 3 N contact without the signature
    monitor = ContactMonitor(threshold=2.0)
    for k in range(50):
        monitor = monitor.update(residuals[k], PUSH[k], WEIGHT[k], payload[k])
        assert not monitor.stopped
    assert monitor.peak < 1e-6
    contact = [residuals[k] + (2.5 if k >= 30 else 0.0) * PUSH[k] for k in range(50)]
    monitor = ContactMonitor(threshold=2.0)
    for k in range(31):
        monitor = monitor.update(contact[k], PUSH[k], WEIGHT[k], payload[k])
    assert monitor.stopped and monitor.force == pytest.approx(2.5)


def test_the_stop_force_of_a_lift_is_what_the_cup_s_lip_has_left_over_the_lever():
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.guard import MIN_STOP_FORCE, Guard

    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    guard = Guard(station, np.eye(3), threshold=5.0)
    lip = station.suction.lip_moment  # 0.64 N m
    assert guard.stop_force(0.1, 0.05) == 5.0  # a light box sealed low: the station's force
    assert guard.stop_force(0.4, 0.12) == pytest.approx((lip - 0.4) / 0.12)  # 2 N: more would peel the seal
    assert guard.stop_force(0.6, 0.12) == MIN_STOP_FORCE  # never under the estimate's noise


def test_a_push_in_that_ends_shallower_than_it_starts_is_watched_along_minus_y():
    from slax_drake.systems.guard import GuardRun, guard_record

    run = GuardRun(ContactMonitor(5.0), 1.0, 2.0, y_start=0.10, y_end=-0.05)
    assert run.direction == -1.0
    assert GuardRun(ContactMonitor(5.0), 1.0, 2.0, y_start=-0.2, y_end=0.15).direction == 1.0
    record = guard_record(run, stopped=True, cup_y=0.0)
    assert record["pushed_in_m"] == pytest.approx(0.10) and record["short_m"] == pytest.approx(0.05)


def test_push_in_forces_lift_the_stop_force_by_the_held_moment_and_raise_a_drag_s_by_its_friction(sim_scenario):
    """The PlannerSystem's guard and plan-step's guarded_push_in take their forces from push_in_forces: a lift's
    stop force is lift_stop_force of the weight's moment about the contact, a drag keeps the station's force and
    expects its floor friction (the action model's pull bound), an object not believed keeps the station's."""
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import SceneObject, planar_pose
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.shelf.actions import GRAVITY, ActionModel, Suction, object_mass
    from slax_drake.shelf.tool import tool_config
    from slax_drake.systems.guard import held_moment, lift_stop_force, push_in_forces

    model = ActionModel(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera).position,
                        tool_config(sim_scenario, "station"))
    box = SceneObject("object_0", "box", (0.10, 0.10, 0.20), planar_pose(0.05, -0.10, 0.10, 0.0), mass=0.8)
    lift = Suction("object_0", (0.05, -0.15, 0.12), 0.0, 0.2, guarded=True)  # the contact 5 cm in front of the centre
    mass = object_mass(box, model.tool.physics.object_density, model.tool.physics)
    assert held_moment(model, box, lift) == pytest.approx(mass * GRAVITY * 0.05)
    stop, expected = push_in_forces(lift, box, model, 5.0, 0.64)
    assert expected == 0.0 and stop == pytest.approx(lift_stop_force(5.0, 0.64, mass * GRAVITY * 0.05, 0.12))
    assert stop <= 5.0
    drag = Suction("object_0", (0.05, -0.15, 0.12), 0.0, 0.2, drag=True, guarded=True)
    stop, expected = push_in_forces(drag, box, model, 5.0, 0.64)
    assert stop == 5.0 and expected == pytest.approx(model.drag_limits(box, 0.12).pull) and expected > 0.0
    assert push_in_forces(lift, None, model, 5.0, 0.64) == (5.0, 0.0)


class _LineModel:
    """A stand-in EffortModel: the cup at q[0] along world +y, efforts = the push signature times the force."""

    push = np.eye(9)[1]
    weight = np.eye(9)[2]

    def effort(self, q, v, a):
        return np.zeros(9)

    def signatures(self, q, push_W, v, a):
        return self.push, self.weight, np.zeros(9)

    def cup_position(self, q):
        return np.array([0.0, float(q[0]), 0.0])


def test_a_drag_s_push_in_bears_its_friction_turning_over_and_stops_on_contact_once_it_slides():
    """A drag's push-in starts with the pull's friction loaded the other way: until the cup has pushed in
    DRAG_REBASE_TRAVEL the guard stops only over twice the friction bound (plus the stop force); then it takes its
    baseline again, sliding, and stops at the stop force over it."""
    from types import SimpleNamespace

    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.guard import DRAG_REBASE_TRAVEL, ContactMonitor, Guard, GuardRun, guard_record

    guard = Guard(load_station_scenario("sim_configs/station_sim_shelf.yaml"), np.eye(3), threshold=5.0)
    guard.model = _LineModel()
    motion = SimpleNamespace(trajectory=SimpleNamespace(times=np.array([0.0, 10.0]), a=np.zeros((2, 9))))
    friction = 10.0
    run = GuardRun(ContactMonitor(5.0, 2.0 * friction), 0.0, 10.0, 0.0, 0.3, rebase_at=DRAG_REBASE_TRAVEL,
                   friction=friction)

    def sample(run, y, force):
        return guard.observe(run, motion, 1.0, np.array([y] + [0.0] * 8), np.zeros(9), force * _LineModel.push)

    # the friction turning over: 2 x 10 N from the baseline, the cup barely moving; no stop at 19.6 N
    run = sample(run, 0.0, -9.8)  # the pull's friction still loaded the other way: the baseline
    for y, f in [(0.0005, 0.0), (0.001, 5.0), (0.002, 9.8)]:
        run = sample(run, y, f)
        assert not run.monitor.stopped
    assert run.monitor.peak == pytest.approx(19.6)
    # sliding at 9.8 N past 1 cm: the baseline is taken again; the friction is in it
    run = sample(run, DRAG_REBASE_TRAVEL + 0.001, 9.8)
    assert run.rebase_at == 0.0 and run.monitor.expected == 0.0 and run.monitor.force == 0.0
    run = sample(run, 0.05, 9.8 + 4.0)
    assert not run.monitor.stopped
    run = sample(run, 0.06, 9.8 + 6.0)  # a hidden object: 6 N more than sliding
    assert run.monitor.stopped
    record = guard_record(run, stopped=True)
    assert record["rebased"] and record["friction_n"] == 10.0 and record["threshold_n"] == 5.0
    # blocked before it slides: stops once past twice the friction and the stop force
    run = GuardRun(ContactMonitor(5.0, 2.0 * friction), 0.0, 10.0, 0.0, 0.3, rebase_at=DRAG_REBASE_TRAVEL,
                   friction=friction)
    run = sample(sample(run, 0.0, 0.0), 0.0, 0.0)
    run = sample(run, 0.0, 24.0)
    assert not run.monitor.stopped
    run = sample(run, 0.0, 26.0)
    assert run.monitor.stopped and not guard_record(run, stopped=True)["rebased"]


def test_a_stop_before_the_objects_leading_face_is_past_the_boards_edge_is_the_edge(sim_scenario):
    """A lifted object carried out of the shelf and pushed back in: a contact while its believed leading face (its
    back, along S +y) is within EDGE_BAND of the opening is the board's front edge, retried once; deeper, on a drag,
    on a carry across inside the shelf, or once retried, it is a contact like any other."""
    import dataclasses

    from slax_drake.scene.model import SceneObject, planar_pose
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.shelf.actions import SEAL_PRESS, Suction
    from slax_drake.systems.guard import EDGE_BAND, GuardRun, at_board_edge, edge_stop_cup_y

    shelf = shelf_of(sim_scenario)
    y_open = -shelf.depth / 2.0
    obj = SceneObject("object_1", "box", (0.08, 0.10, 0.12), planar_pose(0.1, y_open + 0.10, 0.06, 0.0))
    lift = Suction("object_1", (0.1, y_open + 0.05, 0.06), -0.2, y_open + 0.12, guarded=True)
    cup_at_seal = y_open + 0.05 + SEAL_PRESS  # the leading face is 0.10 m ahead of the cup (centre 0.05 + 0.05)
    y_start = y_open - 0.12  # the push-in starts with the object out of the shelf, its back 2 cm outside
    edge = edge_stop_cup_y(lift, obj, shelf, y_start)
    assert edge == pytest.approx(y_open + EDGE_BAND - (y_open + 0.15 - cup_at_seal))
    run = GuardRun(ContactMonitor(threshold=5.0), 0.0, 1.0, y_start, y_start + 0.2, edge_cup_y=edge)
    assert at_board_edge(run, y_start + 0.02)  # 2 cm in: the back has just reached the opening
    assert at_board_edge(run, edge) and not at_board_edge(run, edge + 0.001)
    assert not at_board_edge(dataclasses.replace(run, edge_stop={"stopped": True}), y_start + 0.02)  # retried once
    assert not at_board_edge(dataclasses.replace(run, y_end=y_start - 0.1), y_start - 0.05)  # a push-in out
    assert edge_stop_cup_y(dataclasses.replace(lift, drag=True), obj, shelf, y_start) is None
    assert edge_stop_cup_y(lift, None, shelf, y_start) is None
    assert edge_stop_cup_y(lift, obj, shelf, y_open - 0.05) is None  # its back inside the opening already
