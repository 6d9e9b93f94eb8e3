"""MJCF models of the testbed's mechanisms, for the MuJoCo peer of the settle benchmark.

Each model is generated from the case set's `params` with the same geometry, masses, inertias
and force laws as the testbed's `src/mechanisms/<name>/build.rs`, and compiled once per case
set. A case changes only run-time fields (tendon ranges) and the state (`qpos`, mocap
poses), so that every case of a set runs on the same compiled `MjModel`.

Conventions: SI units, angles in radians (`compiler angle="radian"`), no gravity (both papers
are quasi-static without gravity; mohr2011's optional payload weight is an applied force on
the end-effector only, as in the testbed). Every node of the testbed's structure is a site of
the same name on the same body, so that the settle criterion can watch the same points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

# --------------------------------------------------------------------------------------------
# Solver settings (one set per benchmark variant, chosen in peer.py)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SolverSettings:
    """Everything a variant may change; the mechanism's geometry and force laws never change."""

    timestep_s: float
    # MJCF names: "Euler", "implicitfast", "implicit", "discrete", "RK4".
    integrator: str = "Euler"
    # "Newton", "CG" or "PGS".
    solver: str = "Newton"
    iterations: int = 100
    tolerance: float = 1e-8
    ls_iterations: int = 50
    # Constraint softness of every equality and limit row (MJCF solref / solimp). A negative
    # solref is MuJoCo's direct (stiffness, damping) form.
    solref: tuple[float, float] = (0.02, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.9, 0.95, 0.001, 0.5, 2.0)
    # MuJoCo's refsafe flag: clamp timeconst to >= 2 dt (Euler/implicit*), or replace rows the
    # step cannot resolve (discrete). Disabling it lets a small timeconst through.
    refsafe: bool = True
    # Viscous damping of the damped joints [N m s/rad] (ji2014's pivot D1, mohr2011's universal
    # joints and knees); None: the case set's (c_D1, c_joint), as the testbed.
    joint_damping_nms_per_rad: float | None = None
    # Viscous damping along mohr2011's cables [N s/m] (none in the testbed). Zero at rest, so
    # the equilibrium is unchanged; MuJoCo applies it to slack cables too.
    cable_damping_n_s_per_m: float = 0.0

    def joint_damping_or(self, case_set_damping_nms_per_rad: float) -> float:
        if self.joint_damping_nms_per_rad is None:
            return case_set_damping_nms_per_rad
        return self.joint_damping_nms_per_rad

    def option_xml(self) -> str:
        flags = "" if self.refsafe else '<flag refsafe="disable"/>'
        return (
            f'<option timestep="{self.timestep_s!r}" integrator="{self.integrator}" '
            f'solver="{self.solver}" iterations="{self.iterations}" tolerance="{self.tolerance!r}" '
            f'ls_iterations="{self.ls_iterations}" gravity="0 0 0">{flags}</option>'
        )

    def default_xml(self) -> str:
        solref = " ".join(repr(float(v)) for v in self.solref)
        solimp = " ".join(repr(float(v)) for v in self.solimp)
        return (
            "<default>"
            f'<equality solref="{solref}" solimp="{solimp}"/>'
            f'<tendon solreflimit="{solref}" solimplimit="{solimp}"/>'
            "</default>"
        )


def vec(v) -> str:
    """An MJCF vector attribute at full double precision."""
    return " ".join(repr(float(x)) for x in v)


# --------------------------------------------------------------------------------------------
# Small geometry helpers (rotations about unit axes, signed angles)
# --------------------------------------------------------------------------------------------

Z_AXIS = np.array([0.0, 0.0, 1.0])


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def rotation(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """Rotation matrix of `angle_rad` about the unit vector `axis` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle_rad) * k + (1.0 - math.cos(angle_rad)) * (k @ k)


def signed_angle(a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> float:
    """Angle [rad] that turns `a` into `b` about `axis` (both orthogonal to `axis`)."""
    return math.atan2(float(np.dot(np.cross(a, b), axis)), float(np.dot(a, b)))


def matrix_to_quat(r: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, r.reshape(9))
    return q


# --------------------------------------------------------------------------------------------
# Common peer machinery
# --------------------------------------------------------------------------------------------


class MechanismPeer:
    """One compiled model of a mechanism and the per-case operations on it."""

    #: Node names, in the testbed's structure order (each is a site of the same name).
    node_names: tuple[str, ...] = ()

    def __init__(self, xml: str):
        self.xml = xml
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self.site_of = {
            n: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, n) for n in self.node_names
        }
        # Every site is a node, so the settle check reads `site_xpos` whole.
        assert sorted(self.site_of.values()) == list(range(self.model.nsite)), "a site that is not a node"

    def node_positions(self) -> np.ndarray:
        """Positions [m] of every node (site order) of the state whose forward pass is in `data`."""
        return self.data.site_xpos

    def node(self, name: str) -> np.ndarray:
        """Position [m] of one node (see `node_positions`)."""
        return self.data.site_xpos[self.site_of[name]]

    def start_mismatch_m(self, start_nodes: dict[str, list[float]]) -> float:
        """Largest distance [m] between the model's nodes and `start_nodes` after `set_case`."""
        mujoco.mj_kinematics(self.model, self.data)
        got = np.array([self.node(n) for n in self.node_names])
        want = np.array([start_nodes[n] for n in self.node_names])
        return float(np.max(np.linalg.norm(got - want, axis=1)))

    def efc_force_of(self, constraint_type: int, object_id: int) -> float:
        """Force [N or N m] of the active constraint row of this type and object, 0 if inactive."""
        d = self.data
        rows = np.flatnonzero((d.efc_type[: d.nefc] == constraint_type) & (d.efc_id[: d.nefc] == object_id))
        return float(d.efc_force[rows[0]]) if rows.size else 0.0

    # To be provided by each mechanism.
    def set_case(self, inputs: dict[str, float], start_nodes: dict[str, list[float]]) -> None:
        raise NotImplementedError

    def observe(self) -> dict[str, float]:
        raise NotImplementedError


# --------------------------------------------------------------------------------------------
# ji2014: planar tensegrity parallel mechanism (Ji, Li, Lin 2014)
# --------------------------------------------------------------------------------------------

#: Angle between the platform sides D1D3 and D1D2 (equilateral triangle) [rad].
JI2014_PLATFORM_CORNER_RAD = math.pi / 3.0


class Ji2014(MechanismPeer):
    """Base C1C2C3 fixed; the actuator rod's tip at D1 = L3 (cos theta1, sin theta1); the
    platform D1D2D3 on a z hinge at the tip with viscous damping c_D1; springs K1 (D2-C2) and
    K2 (D3-C3) as spatial tendons of stiffness K1, K2 and zero free length.

    The testbed drives the actuator (housing turned by theta1, rod slid by L3) as kinematic
    degrees of freedom: placed, never integrated. MuJoCo's kinematic bodies are mocap bodies,
    so the rod is a mocap body placed per case at its tip, turned by theta1, and the platform
    hangs from it on its hinge. (A prismatic joint locked by an equality constraint was tried:
    the soft lock left 1e-6 to 1e-5 errors and needed 200 steps, see README.md.) The
    actuator's axial force F_L3 is then, as in the testbed, minus the load of the springs on
    the platform along C1->D1.

    Reference configuration: the rod's frame on C1, its x axis along the actuator; platform
    hinge coordinate 0 with the side D1D3 along the rod, so the coordinate is theta2 - theta1.
    """

    node_names = ("C1", "C2", "C3", "L3_tip", "D1", "D2", "D3")

    def __init__(self, params: dict[str, float], settings: SolverSettings):
        side_m = params["L"]
        platform_mass_kg = params["m_platform"]
        sqrt3 = math.sqrt(3.0)
        c1, c2, c3 = (0.0, 0.0, 0.0), (-side_m, -sqrt3 * side_m, 0.0), (side_m, -sqrt3 * side_m, 0.0)
        # Platform nodes in its own frame (origin D1, x along D1D3).
        d2_local = side_m * np.array(
            [math.cos(JI2014_PLATFORM_CORNER_RAD), math.sin(JI2014_PLATFORM_CORNER_RAD), 0.0]
        )
        d3_local = np.array([side_m, 0.0, 0.0])
        centroid_local = (d2_local + d3_local) / 3.0
        # Three point masses m/3 at the vertices: I_z = m L^2 / 3, I_x = I_y = m L^2 / 6.
        ml2 = platform_mass_kg * side_m * side_m
        platform_inertia = (ml2 / 6.0, ml2 / 6.0, ml2 / 3.0)
        pivot_damping = settings.joint_damping_or(params["c_D1"])
        xml = f"""
<mujoco model="ji2014">
  <compiler angle="radian"/>
  {settings.option_xml()}
  {settings.default_xml()}
  <worldbody>
    <site name="C1" pos="{vec(c1)}"/>
    <site name="C2" pos="{vec(c2)}"/>
    <site name="C3" pos="{vec(c3)}"/>
    <body name="actuator_rod" mocap="true" pos="{vec(c1)}">
      <site name="L3_tip" pos="0 0 0"/>
      <body name="platform">
        <joint name="D1" type="hinge" axis="0 0 1" damping="{pivot_damping!r}"/>
        <inertial pos="{vec(centroid_local)}" mass="{platform_mass_kg!r}"
                  diaginertia="{vec(platform_inertia)}"/>
        <site name="D1" pos="0 0 0"/>
        <site name="D2" pos="{vec(d2_local)}"/>
        <site name="D3" pos="{vec(d3_local)}"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <spatial name="K1" stiffness="{params['K1']!r}" springlength="0">
      <site site="D2"/><site site="C2"/>
    </spatial>
    <spatial name="K2" stiffness="{params['K2']!r}" springlength="0">
      <site site="D3"/><site site="C3"/>
    </spatial>
  </tendon>
</mujoco>
"""
        super().__init__(xml)
        m = self.model
        self.stiffness_n_per_m = (params["K1"], params["K2"])
        self.rod_mocap = m.body_mocapid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "actuator_rod")]
        self.pivot_qpos = m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "D1")]
        self.actuator_axis = (1.0, 0.0, 0.0)

    def set_case(self, inputs, start_nodes):
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        theta1, l3 = inputs["theta1"], inputs["L3"]
        self.actuator_axis = (math.cos(theta1), math.sin(theta1), 0.0)
        d.mocap_pos[self.rod_mocap] = [l3 * a for a in self.actuator_axis]
        d.mocap_quat[self.rod_mocap] = (math.cos(0.5 * theta1), 0.0, 0.0, math.sin(0.5 * theta1))
        d1, d3 = np.asarray(start_nodes["D1"]), np.asarray(start_nodes["D3"])
        theta2 = math.atan2(d3[1] - d1[1], d3[0] - d1[0])
        d.qpos[self.pivot_qpos] = theta2 - theta1

    def observe(self):
        d = self.data
        k1, k2 = self.stiffness_n_per_m
        # Plain floats: a handful of numbers, where numpy's per-call cost would dominate.
        c2, c3, d1, d2, d3 = (d.site_xpos[self.site_of[n]].tolist() for n in ("C2", "C3", "D1", "D2", "D3"))
        axis_x, axis_y, axis_z = self.actuator_axis
        # Zero free length: spring K pulls its platform node towards its base node with the
        # force k (base - platform), of magnitude k times the tendon length.
        on_platform = [k1 * (c2[i] - d2[i]) + k2 * (c3[i] - d3[i]) for i in range(3)]
        return {
            "theta2": math.atan2(d3[1] - d1[1], d3[0] - d1[0]),
            "x": d3[0],
            "y": d3[1],
            "F_K1": k1 * float(d.ten_length[0]),
            "F_K2": k2 * float(d.ten_length[1]),
            # The actuator balances the springs at D1: its axial force on D1 along C1->D1.
            "F_L3": -(on_platform[0] * axis_x + on_platform[1] * axis_y + on_platform[2] * axis_z),
        }


# --------------------------------------------------------------------------------------------
# mohr2011: translational 3-DOF tensegrity mechanism (Mohr, Arsenault 2011)
# --------------------------------------------------------------------------------------------

#: The six cables in the testbed's order (t1..t6, Eq. 21): (base node, end-effector node, rho).
MOHR2011_CABLES = ((2, 3, 1), (1, 3, 2), (1, 2, 3), (3, 2, 1), (3, 1, 2), (2, 1, 3))
#: Link inertia: an isotropic m (l_o/2)^2 / 12 = m l_o^2 / 48, as the testbed's build.rs.
MOHR2011_LINK_INERTIA_PER_MASS_LO2 = 1.0 / 48.0


class Mohr2011(MechanismPeer):
    """Base A1A2A3 fixed; end-effector B1B2B3 on three two-link virtual compression springs
    (universal joint at A_i: first axis e1_i = z x a_i / |a_i| fixed in the base, second axis
    the knee axis; knee hinge with torsion spring kappa, at rest straight; spherical joint at
    B_i); six cables as spatial tendons, tension-only and inextensible (limited, range
    [0, rho]) or elastic (a dead-band spring, k_cable > 0).

    The tree is leg 1 -> end-effector (ball joint at B1), as the testbed's multibody chain; legs
    2 and 3 are closed at B2 and B3 by connect equalities (soft, like the cable limits).

    Reference configuration (qpos = 0): every leg straight and vertical above A_i (lower link
    A_i -> A_i + l_o/2 z, upper link up to A_i + l_o z), second universal axis e2_i = e1_i x z;
    the end-effector at the top of leg 1 with the identity orientation.
    """

    node_names = ("A1", "A2", "A3", "B1", "B2", "B3") + tuple(
        f"{n}{i}{s}" for i in (1, 2, 3) for n, s in (("K", ""), ("A", "_leg"), ("K", "_upper"), ("B", "_leg"))
    )

    def __init__(self, params: dict[str, float], settings: SolverSettings):
        if params.get("straight", 0.0) != 0.0:
            raise NotImplementedError("mohr2011 peer: only the paper's two-link springs (straight = 0)")
        lb, lo = params["lb"], params["lo"]
        half_lo = 0.5 * lo
        sqrt3 = math.sqrt(3.0)
        # Eq. 1: base nodes a_i; Eq. 2: end-effector nodes B_i = p - a_i.
        self.base = lb * np.array(
            [[-0.5, -sqrt3 / 6.0, 0.0], [0.5, -sqrt3 / 6.0, 0.0], [0.0, sqrt3 / 3.0, 0.0]]
        )
        self.e1 = np.array([unit(np.cross(Z_AXIS, a)) for a in self.base])
        self.e2_ref = np.array([np.cross(e1, Z_AXIS) for e1 in self.e1])
        damping = settings.joint_damping_or(params["c_joint"])
        link_mass = params["m_link"]
        link_inertia = link_mass * lo * lo * MOHR2011_LINK_INERTIA_PER_MASS_LO2
        platform_mass = params["m_platform"]
        ml2 = platform_mass * lb * lb
        platform_inertia = (ml2 / 6.0, ml2 / 6.0, ml2 / 3.0)
        self.cable_stiffness = params.get("k_cable", 0.0)
        self.payload_n = np.array([0.0, 0.0, platform_mass * params.get("g_z", 0.0)])

        def leg(i: int, end_effector: str) -> str:
            n = i + 1
            link = (
                f'<inertial pos="0 0 {half_lo / 2.0!r}" mass="{link_mass!r}" '
                f'diaginertia="{vec((link_inertia,) * 3)}"/>'
            )
            return f"""
    <body name="leg{n}_lower" pos="{vec(self.base[i])}">
      <joint name="U{n}_base" type="hinge" axis="{vec(self.e1[i])}" damping="{damping!r}"/>
      <joint name="U{n}_knee" type="hinge" axis="{vec(self.e2_ref[i])}" damping="{damping!r}"/>
      {link}
      <site name="A{n}_leg" pos="0 0 0"/>
      <site name="K{n}" pos="0 0 {half_lo!r}"/>
      <body name="leg{n}_upper" pos="0 0 {half_lo!r}">
        <joint name="knee{n}" type="hinge" axis="{vec(self.e2_ref[i])}" stiffness="{params['kappa']!r}"
               springref="0" damping="{damping!r}"/>
        {link}
        <site name="K{n}_upper" pos="0 0 0"/>
        <site name="B{n}_leg" pos="0 0 {half_lo!r}"/>
        {end_effector}
      </body>
    </body>"""

        # End-effector frame at B1 (the ball joint), world-aligned at the reference; its nodes
        # B_j = B1 + (a_1 - a_j), its centroid B1 + a_1.
        ee_sites = "".join(
            f'<site name="B{j + 1}" pos="{vec(self.base[0] - self.base[j])}"/>' for j in range(3)
        )
        end_effector = f"""
        <body name="end_effector" pos="0 0 {half_lo!r}">
          <joint name="S1" type="ball"/>
          <inertial pos="{vec(self.base[0])}" mass="{platform_mass!r}" diaginertia="{vec(platform_inertia)}"/>
          {ee_sites}
        </body>"""
        if self.cable_stiffness > 0.0:
            # Tension-only elastic: a dead-band spring, slack below the commanded length
            # (set per case as the band's upper end).
            cable_law = f'stiffness="{self.cable_stiffness!r}" springlength="0 0"'
        else:
            # Inextensible and tension-only: an upper length limit (set per case).
            cable_law = 'limited="true" range="0 1"'
        cable_damping = f'damping="{settings.cable_damping_n_s_per_m!r}"'
        cables = "".join(
            f'<spatial name="A{a}B{b}" {cable_law} {cable_damping}>'
            f'<site site="A{a}"/><site site="B{b}"/></spatial>'
            for a, b, _ in MOHR2011_CABLES
        )
        base_sites = "".join(f'<site name="A{i + 1}" pos="{vec(self.base[i])}"/>' for i in range(3))
        xml = f"""
<mujoco model="mohr2011">
  <compiler angle="radian"/>
  {settings.option_xml()}
  {settings.default_xml()}
  <worldbody>
    {base_sites}
    {leg(0, end_effector)}
    {leg(1, "")}
    {leg(2, "")}
  </worldbody>
  <equality>
    <connect name="close_leg2" site1="B2_leg" site2="B2"/>
    <connect name="close_leg3" site1="B3_leg" site2="B3"/>
  </equality>
  <tendon>{cables}</tendon>
</mujoco>
"""
        super().__init__(xml)
        m = self.model
        leg_joints = [name for n in (1, 2, 3) for name in (f"U{n}_base", f"U{n}_knee", f"knee{n}")]
        self.qpos_of = {
            name: m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)]
            for name in ["S1", *leg_joints]
        }
        self.end_effector = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "end_effector")
        self.tendon_ids = [
            mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, f"A{a}B{b}") for a, b, _ in MOHR2011_CABLES
        ]

    def leg_coordinates(self, i: int, start_nodes) -> tuple[float, float, float, np.ndarray]:
        """Universal angles (about e1, then about the carried e2), knee bend [rad] and the upper
        link's world rotation that put leg i's A, K, B nodes where `start_nodes` has them."""
        n = i + 1
        a, k, b = (np.asarray(start_nodes[name]) for name in (f"A{n}", f"K{n}", f"B{n}_leg"))
        e1, e2_ref = self.e1[i], self.e2_ref[i]
        lower, upper = unit(k - a), unit(b - k)
        # The testbed's knee axis e2 = e1 x (B - A) / |.| (normal of the leg's plane).
        e2 = unit(np.cross(e1, b - a))
        about_e1 = signed_angle(e2_ref, e2, e1)
        lower_in_first_frame = rotation(e1, -about_e1) @ lower
        about_e2 = signed_angle(Z_AXIS, lower_in_first_frame, e2_ref)
        bend = signed_angle(lower, upper, e2)
        upper_rotation = rotation(e1, about_e1) @ rotation(e2_ref, about_e2) @ rotation(e2_ref, bend)
        return about_e1, about_e2, bend, upper_rotation

    def set_case(self, inputs, start_nodes):
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        for j, (_, _, rho) in enumerate(MOHR2011_CABLES):
            length = inputs[f"rho{rho}"]
            if self.cable_stiffness > 0.0:
                m.tendon_lengthspring[self.tendon_ids[j]] = (0.0, length)
            else:
                m.tendon_range[self.tendon_ids[j]] = (0.0, length)
        upper1 = None
        for i in range(3):
            about_e1, about_e2, bend, upper_rotation = self.leg_coordinates(i, start_nodes)
            n = i + 1
            d.qpos[self.qpos_of[f"U{n}_base"]] = about_e1
            d.qpos[self.qpos_of[f"U{n}_knee"]] = about_e2
            d.qpos[self.qpos_of[f"knee{n}"]] = bend
            if i == 0:
                upper1 = upper_rotation
        # The end-effector starts with the identity orientation (pure translation): the ball
        # joint undoes the rotation of leg 1's upper link.
        q = self.qpos_of["S1"]
        d.qpos[q : q + 4] = matrix_to_quat(upper1.T)
        if np.any(self.payload_n):
            d.xfrc_applied[self.end_effector, :3] = self.payload_n

    def observe(self):
        d = self.data
        b = [self.node(f"B{i}") for i in (1, 2, 3)]
        a = [self.node(f"A{i}") for i in (1, 2, 3)]
        centroid = (b[0] + b[1] + b[2]) / 3.0
        q = d.xquat[self.end_effector]  # (w, x, y, z)
        values = {
            "x": float(centroid[0]),
            "y": float(centroid[1]),
            "z": float(centroid[2]),
            "rotation": 2.0 * math.atan2(float(np.linalg.norm(q[1:])), abs(float(q[0]))),
        }
        for i in range(3):
            values[f"l{i + 1}"] = float(np.linalg.norm(b[i] - a[i]))
        for j, t in enumerate(self.tendon_ids):
            if self.cable_stiffness > 0.0:
                stretch = d.ten_length[t] - self.model.tendon_lengthspring[t, 1]
                tension = self.cable_stiffness * max(0.0, float(stretch))
            else:
                # The upper-limit row's force is the cable tension (0 while slack).
                tension = self.efc_force_of(mujoco.mjtConstraint.mjCNSTR_LIMIT_TENDON, t)
            values[f"t{j + 1}"] = tension
        return values


MECHANISMS = {"ji2014": Ji2014, "mohr2011": Mohr2011}
