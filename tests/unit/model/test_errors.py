"""Bad input raises the project's own errors, naming the culprit."""

import math

import numpy as np
import pytest

from tests.support.culprit import assert_names_culprit, bad_cases
from uvms_qp import (
    InputError,
    Model,
    ModelError,
    ModelFileError,
    NonFiniteError,
    ShapeError,
    UnknownFrameError,
    UnknownModelError,
    UnknownNameError,
    load_model,
)
from uvms_qp.model import DHRow, Vehicle


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


def test_unknown_frame_lists_the_known_frames(rov):
    state = rov.state(rov.home())
    for call in (
        lambda: state.pose("elbow"),
        lambda: state.jacobian("elbow"),
        lambda: state.arm_jacobian("elbow"),
        lambda: state.pose_in("tool", "elbow"),
        lambda: rov.frame_pose(rov.home(), "elbow"),
        lambda: rov.frame_id("elbow"),
    ):
        with pytest.raises(UnknownFrameError) as info:
            call()
        message = str(info.value)
        assert "'elbow'" in message
        for frame in ("world", "vehicle", "arm_base", "tool", "jaws_base_link"):
            assert frame in message
        assert info.value.known == rov.frames


def test_wrong_configuration_length(rov):
    with pytest.raises(ShapeError, match=r"q: expected shape \(11,\)"):
        rov.state(np.zeros(10))
    with pytest.raises(ShapeError, match="q"):
        rov.integrate(np.zeros(12), np.zeros(10), 0.1)
    with pytest.raises(ShapeError, match="joints: expected length 4"):
        rov.configuration(np.zeros(6), np.zeros(5))
    with pytest.raises(ShapeError, match="eta: expected length 6"):
        rov.configuration(np.zeros(3), np.zeros(4))


def test_wrong_zeta_length(rov):
    with pytest.raises(ShapeError, match="zeta: expected length 10, got 9"):
        rov.integrate(rov.home(), np.zeros(9), 0.1)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_configuration(rov, bad):
    q = rov.home()
    q[8] = bad
    with pytest.raises(NonFiniteError, match=r"q contains .* index 8"):
        rov.state(q)
    with pytest.raises(NonFiniteError, match="q"):
        rov.check_configuration(q)


def test_non_finite_zeta_and_dt(rov):
    with pytest.raises(NonFiniteError, match="zeta"):
        rov.integrate(rov.home(), [0, 0, 0, 0, 0, 0, 0, math.nan, 0, 0], 0.1)
    with pytest.raises(NonFiniteError, match="dt"):
        rov.integrate(rov.home(), np.zeros(10), math.inf)


@pytest.mark.parametrize("dt", [-0.1, 0.0])
def test_integrate_rejects_a_duration_that_is_not_positive(rov, dt):
    with pytest.raises(InputError, match=f"^dt: expected a positive number, got {dt}$"):
        rov.integrate(rov.home(), np.zeros(10), dt)
    zeta = np.linspace(-0.3, 0.3, rov.nv)  # backwards is a negated zeta
    back = rov.integrate(rov.integrate(rov.home(), zeta, 0.1), -zeta, 0.1)
    np.testing.assert_allclose(back, rov.home(), atol=1e-12)

def test_quaternion_drift_is_normalised_and_large_errors_rejected(rov):
    q = rov.home()
    q[3:7] *= 1.0 + 1e-5
    fixed = rov.check_configuration(q)
    assert np.linalg.norm(fixed[3:7]) == pytest.approx(1.0, abs=1e-15)
    q[3:7] = [0.0, 0.0, 0.0, 2.0]
    with pytest.raises(InputError, match=r"quaternion q\[3:7\]"):
        rov.state(q)


def test_missing_urdf(tmp_path):
    path = tmp_path / "nowhere.urdf"
    with pytest.raises(ModelFileError, match=r"nowhere\.urdf.*no such file") as info:
        Model.from_urdf(path)
    assert isinstance(info.value, FileNotFoundError)


def test_missing_urdf_given_relative_is_named_resolved(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ModelFileError) as info:
        Model.from_urdf("arms/nowhere.urdf")
    assert str(info.value) == (f"URDF 'arms/nowhere.urdf': no such file ({tmp_path}/arms/"
                               f"nowhere.urdf, relative to the working directory {tmp_path})")


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("<robot name='x'><link name='a'>", "does not parse as XML"),
        ("<model/>", "root element is <model>"),
        (
            "<robot name='x'><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
            "<parent link='a'/><child link='b'/><axis xyz='0 0 1'/></joint></robot>",
            "joint 'j' .*needs <limit",
        ),
        (
            "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
            "<child link='zz'/><limit lower='0' upper='1' velocity='1' effort='1'/>"
            "</joint></robot>",
            "child link 'zz' is not a <link>",
        ),
        (
            "<robot name='x'><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
            "<parent link='a'/><child link='b'/><origin xyz='0 zero 0'/>"
            "<limit lower='0' upper='1' velocity='1' effort='1'/></joint></robot>",
            r"joint 'j' <origin xyz>: expected 3 finite numbers, got '0 zero 0'",
        ),
    ],
)
def test_unparsable_urdf_names_the_file(tmp_path, text, match):
    path = tmp_path / "broken.urdf"
    path.write_text(text)
    with pytest.raises(ModelFileError, match=match) as info:
        Model.from_urdf(path)
    assert "broken.urdf" in str(info.value)


def test_unsupported_urdf_joint_and_ambiguous_tool(tmp_path):
    path = tmp_path / "cont.urdf"
    path.write_text(
        "<robot name='x'><link name='a'/><link name='b'/><joint name='spin' type='continuous'>"
        "<parent link='a'/><child link='b'/><axis xyz='0 0 1'/></joint></robot>"
    )
    with pytest.raises(ModelError, match="'spin' has type 'continuous'"):
        Model.from_urdf(path)
    path = tmp_path / "fork.urdf"
    limit = "<limit lower='-1' upper='1' velocity='1' effort='1'/>"
    path.write_text(
        "<robot name='x'><link name='a'/><link name='b'/><link name='c'/>"
        f"<joint name='j1' type='revolute'><parent link='a'/><child link='b'/>{limit}</joint>"
        f"<joint name='j2' type='revolute'><parent link='a'/><child link='c'/>{limit}</joint>"
        "</robot>"
    )
    with pytest.raises(ModelError, match="several leaf links"):
        Model.from_urdf(path)
    with pytest.raises(UnknownFrameError, match="'d'; known frames: a, b, c"):
        Model.from_urdf(path, tool="d")
    assert Model.from_urdf(path, tool="c").n_joints == 2


def test_unknown_model_lists_bundled_models():
    with pytest.raises(UnknownModelError, match="'rov'; known models: soylu_planar"):
        load_model("rov")


def test_bad_dh_tables():
    with pytest.raises(InputError, match=r"table\[0\]: expected a DHRow or a mapping"):
        Model.from_dh([(1.0, 0.0, 0.0, 0.0)])
    with pytest.raises(InputError, match=r"table\[1\]: unknown keys \['length'\]"):
        Model.from_dh([{"a": 1.0}, {"length": 1.0}])
    with pytest.raises(NonFiniteError, match=r"table\[0\].d"):
        Model.from_dh([{"a": 1.0, "d": math.nan}])
    with pytest.raises(InputError, match=r"table\[0\]: lower limit 1.0 > upper limit 0.0"):
        Model.from_dh([DHRow(lower=1.0, upper=0.0)])
    with pytest.raises(InputError, match="convention: unknown 'craig'"):
        Model.from_dh([DHRow()], "craig")
    with pytest.raises(ModelError, match="no revolute or prismatic"):
        Model.from_dh([DHRow(kind="fixed")])
    with pytest.raises(ModelError, match="non-empty"):
        Model.from_dh([])
    with pytest.raises(ShapeError, match="joint_names: expected 1 names"):
        Model.from_dh([DHRow()], joint_names=["a", "b"])
    with pytest.raises(ModelError, match="clash with vehicle DOF names"):
        Model.from_dh([DHRow(name="u")])
    with pytest.raises(ModelError, match="reserved"):
        Model.from_dh([DHRow(name="tool")])
    with pytest.raises(ShapeError, match="joint_lower: expected length 1"):
        Model.from_dh([DHRow()], joint_lower=[0.0, 1.0])
    with pytest.raises(ModelError, match="home angle of joint 'joint1' is outside limits"):
        Model.from_dh([DHRow(lower=-1.0, upper=1.0)], home=[1.5])
    with pytest.raises(ModelError, match="joint 'joint2' has lower limit > upper limit"):
        Model.from_dh([DHRow(), DHRow()], joint_lower=[0.0, 2.0], joint_upper=[1.0, 1.0])


def test_bad_mounts_and_vehicles():
    with pytest.raises(InputError, match="mount: the 3x3 block is not a rotation"):
        Model.from_dh([DHRow()], mount=np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(ShapeError, match="mount: expected 4 rows"):
        Model.from_dh([DHRow()], mount=np.eye(3))
    with pytest.raises(InputError, match=r"mount: unknown keys \['xyzz'\]"):
        Model.from_dh([DHRow()], mount={"xyzz": (0, 0, 0)})
    with pytest.raises(InputError, match="unknown spatial DOF 'x'"):
        Vehicle("spatial", actuated=("u", "x"))
    with pytest.raises(InputError, match="vehicle kind: unknown 'boat'"):
        Vehicle("boat")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="vehicle: expected a Vehicle"):
        Model.from_dh([DHRow()], vehicle=3)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="vehicle rate_limit: must be positive"):
        Vehicle("planar", rate_limit=(1.0, 0.0, 1.0))


def test_bad_rows_and_axes_names(rov):
    state = rov.state(rov.home())
    rows = "unknown row set 'linear'; known row sets: twist, position"
    with pytest.raises(UnknownNameError, match=rows):
        state.jacobian("tool", rows="linear")
    axes = "unknown axis convention 'body'; known axis conventions: world, local"
    with pytest.raises(UnknownNameError, match=axes):
        state.jacobian("tool", axes="body")


# ------------------------------------------------------------------------------- URDF content
_LIMIT = "<limit lower='-1' upper='1' velocity='1' effort='1'/>"


def _urdf(tmp_path, joint_body, *, joint_name="j", child="b", extra=""):
    path = tmp_path / "arm.urdf"
    path.write_text(
        "<robot name='x'><link name='a'/><link name='b'/>"
        f"<joint name='{joint_name}' type='revolute'><parent link='a'/><child link='{child}'/>"
        f"{joint_body}</joint>{extra}</robot>"
    )
    return path


@pytest.mark.parametrize(
    ("body", "error", "match"),
    [
        (f"<axis xyz='0 0 0'/>{_LIMIT}", ModelFileError, r"joint 'j' <axis xyz='0 0 0'> is zero"),
        (f"<axis xyz='nan 0 1'/>{_LIMIT}", ModelFileError,
         r"joint 'j' <axis xyz>: expected 3 finite numbers, got 'nan 0 1'"),
        (f"<axis xyz='up'/>{_LIMIT}", ModelFileError, r"joint 'j' <axis xyz>: .* got 'up'"),
        (f"<axis xyz='0 0 1 0'/>{_LIMIT}", ModelFileError, r"joint 'j' <axis xyz>"),
        ("<limit lower='-1' upper='1' velocity='1'/>", ModelFileError,
         r"joint 'j' <limit> has no effort="),
        ("<limit lower='-1' upper='1' effort='1'/>", ModelFileError,
         r"joint 'j' <limit> has no velocity="),
        ("<limit lower='low' upper='1' velocity='1' effort='1'/>", ModelFileError,
         r"joint 'j' <limit lower>: expected 1 finite number, got 'low'"),
        ("<limit lower='-1' upper='nan' velocity='1' effort='1'/>", ModelFileError,
         r"joint 'j' <limit upper>"),
        ("<limit lower='-1' upper='1' velocity='-2' effort='1'/>", ModelFileError,
         r"joint 'j' <limit velocity='-2'> is negative"),
        ("<limit lower='1' upper='-1' velocity='1' effort='1'/>", ModelError,
         r"joint 'j' has lower limit 1.0 >= upper limit -1.0"),
        (f"<mimic joint='other'/>{_LIMIT}", ModelError,
         r"joint 'j' <mimic joint='other'> is not supported"),
    ],
)
def test_malformed_urdf_joints_name_the_element(tmp_path, body, error, match):
    """Silently wrong or refused by Pinocchio without a culprit: each names joint and element."""
    with pytest.raises(error, match=match) as info:
        Model.from_urdf(_urdf(tmp_path, body))
    assert "arm.urdf" in str(info.value)


def test_a_urdf_without_a_moving_joint_is_refused(tmp_path):
    path = tmp_path / "rigid.urdf"
    path.write_text("<robot name='x'><link name='a'/><link name='b'/><joint name='f' type='fixed'>"
                    "<parent link='a'/><child link='b'/></joint></robot>")
    with pytest.raises(ModelError, match="no revolute or prismatic joint"):
        Model.from_urdf(path)


def test_a_joint_named_like_a_link_is_legal(tmp_path):
    """URDF keeps joints and links in separate namespaces; the link stays the public frame."""
    path = _urdf(tmp_path, f"<axis xyz='0 0 1'/>{_LIMIT}", joint_name="b",
                 extra="<link name='c'/><joint name='c' type='fixed'><parent link='b'/>"
                       "<child link='c'/><origin xyz='0.5 0 0'/></joint>")
    model = Model.from_urdf(path, vehicle="fixed")
    assert model.joint_names == ("b",)
    assert {"b", "c"} <= set(model.frames)
    state = model.state(model.configuration(None, [np.pi / 2]))
    np.testing.assert_allclose(state.position("c"), [0.0, 0.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(state.position("tool"), [0.0, 0.5, 0.0], atol=1e-12)


def test_urdf_size_and_chain_length_are_bounded(tmp_path):
    from uvms_qp.model.urdf import MAX_FILE_BYTES, MAX_MOVING_JOINTS

    n = MAX_MOVING_JOINTS + 1
    parts = ["<robot name='c'><link name='l0'/>"]
    for i in range(n):
        parts.append(f"<link name='l{i + 1}'/><joint name='j{i}' type='revolute'>"
                     f"<parent link='l{i}'/><child link='l{i + 1}'/><origin xyz='0 0 0.1'/>"
                     f"<axis xyz='0 0 1'/>{_LIMIT}</joint>")
    parts.append("</robot>")
    path = tmp_path / "long.urdf"
    path.write_text("".join(parts))
    with pytest.raises(ModelError, match=f"{n} moving joints; an arm may have at most "
                                         f"{MAX_MOVING_JOINTS}"):
        Model.from_urdf(path)
    big = tmp_path / "big.urdf"
    big.write_text(_urdf(tmp_path, f"<axis xyz='0 0 1'/>{_LIMIT}").read_text()
                   + "<!--" + " " * MAX_FILE_BYTES + "-->")
    with pytest.raises(ModelFileError, match=f"at most {MAX_FILE_BYTES} bytes"):
        Model.from_urdf(big)


@pytest.mark.parametrize("path", [None, 3, ["arm.urdf"]])
def test_a_urdf_path_must_be_a_path(path):
    with pytest.raises(InputError, match="path: expected a URDF file path"):
        Model.from_urdf(path)


@pytest.mark.parametrize(
    ("value", "what"),
    [(["0"] * 11, "strings"), ([True] + [0.0] * 10, "boolean"), ([0j] * 11, "complex"),
     (np.zeros(11, dtype=complex), "complex"), (np.zeros(11, dtype=bool), "booleans"),
     ([None] * 11, "NoneType")],
)
def test_a_configuration_must_be_real_numbers(rov, value, what):
    """Strings, booleans and complex numbers are refused, not converted (imaginary part lost)."""
    with pytest.raises(InputError, match=f"q: expected real numbers, got .*{what}"):
        rov.state(value)


# ------------------------------------------------------------------ other model inputs
def test_model_bad_inputs(rov: Model) -> None:
    q = rov.neutral()
    with pytest.raises(UnknownFrameError):
        rov.frame_pose(q, ["tool"])  # type: ignore[arg-type]
    state = rov.state(q)
    with pytest.raises(UnknownFrameError):
        state.jacobian(["tool"])  # type: ignore[arg-type]
    with pytest.raises(UnknownFrameError):
        state.arm_jacobian(["tool"])  # type: ignore[arg-type]
    for bad in (-1.0, float("nan"), "x"):
        with pytest.raises(InputError, match="position"):
            rov.random_configuration(0, position=bad)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="rng"):
        rov.random_configuration("seed")  # type: ignore[arg-type]


def test_from_dh_joint_names_must_be_strings() -> None:
    row = {"a": 1.0, "alpha": 0.0, "d": 0.0, "theta": 0.0}
    with pytest.raises(InputError, match=r"joint_names\[0\]"):
        Model.from_dh([row], vehicle="planar", joint_names=[1])  # type: ignore[list-item]
    with pytest.raises(InputError, match="joint_names"):
        Model.from_dh([row], vehicle="planar", joint_names="j1")


def test_integrate_overflow_is_an_error(rov: Model) -> None:
    q = rov.neutral()
    with pytest.raises(NonFiniteError, match="overflow"):
        rov.integrate(q, np.full(rov.nv, 1e154), 1.0)
    # an ordinary step is unaffected
    zeta = np.zeros(rov.nv)
    zeta[0] = 0.5
    q1 = rov.integrate(q, zeta, 2.0)
    assert np.isfinite(q1).all()
    assert rov.state(q1).position("vehicle")[0] == pytest.approx(1.0)


def test_fixed_base_accepts_none_as_the_empty_pose():
    model = load_model("nenchev_pa10_arm")
    joints = model.split(model.home())[1]
    np.testing.assert_array_equal(model.configuration(None, joints), model.home())
    with pytest.raises(ShapeError, match="got length 1"):
        model.configuration([0.0], joints)
    spatial = load_model("wang_9dof")
    with pytest.raises(ShapeError, match="length 6, got None"):
        spatial.configuration(None, spatial.split(spatial.home())[1])


# ------------------------------------------------------------------------------ configurations
# (id, callable taking the model, error type, fragment of the message naming the culprit)
BAD_MODEL = [
    ("q wrong length", lambda m: m.state(np.zeros(m.nq - 1)), ShapeError, "q"),
    ("q inf", lambda m: m.state(np.full(m.nq, math.inf)), NonFiniteError, "q"),
    ("quaternion far from unit", lambda m: m.state(np.r_[np.zeros(3), 0, 0, 0, 3.0,
                                                         np.zeros(4)]), InputError, "quaternion"),
    ("eta wrong length", lambda m: m.configuration(np.zeros(5), np.zeros(4)), ShapeError,
     "eta"),
]


@pytest.mark.parametrize("build, error, fragment", bad_cases(BAD_MODEL))
def test_bad_configuration_is_raised_with_its_culprit(rov, build, error, fragment):
    assert_names_culprit(build, error, fragment, rov)
