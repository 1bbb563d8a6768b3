"""Typed stubs of the featherdrive module (python/module.cpp, python/bind_*.cpp): articulated
robots in reduced coordinates with implicit PD joint drives solved as NVIDIA PhysX 5 does (PGS
or TGS).

Vectors read from a Simulation are read-only numpy views onto its state that follow later steps
and stay valid for its life (no call moves them; load_checkpoint restores in place); copy them
(numpy.array(sim.q)) to keep a snapshot. Batch states are (N, n) views of the same kind;
settings read back are copies.

A Simulation or Batch may be shared between threads: each call holds the object's lock (a copy
from Batch.sim(i) shares the batch's), so calls run one after another, each whole; step() runs
without the GIL. Views are not synchronised: read them when no step runs. Ctrl-C interrupts
step() between two steps (KeyboardInterrupt, state of the last whole step).

Integers are int, numpy integers or objects with __index__ (not bool, not float: TypeError),
range-checked in 64 bits (ValueError naming the argument and value). Bad values raise
ValueError, wrong types TypeError, a diverging step RuntimeError (DivergenceError)."""

import enum
import os
from typing import Literal, Sequence, SupportsIndex, Union, overload

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
Vector = npt.NDArray[np.float64]
PathLike = Union[str, os.PathLike[str]]
Int = SupportsIndex
"""An integer: int, a numpy integer or anything with __index__ (bool is refused)."""
Joint = Union[str, Int]
"""A joint name (a spherical joint's axes: 'ball:twist', 'ball:swing1', 'ball:swing2'), or a
dof index."""

class DivergenceError(RuntimeError):
    """A step would produce a non-finite value; the state is that before the step."""

class ModelError(ValueError):
    """Bad model input (ModelBuilder): names the link or joint, field and value."""

class InputError(ValueError):
    """A bad input file (URDF, scene): names the file, element or key and value."""

class JointType(enum.Enum):
    """The type of a link's inbound joint."""
    fixed = 0
    revolute = 1
    prismatic = 2
    spherical = 3
    floating = 4

class DriveType(enum.Enum):
    """The kind of a joint drive."""
    none = 0
    force = 1
    acceleration = 2

class SolverType(enum.Enum):
    """The constraint solver."""
    pgs = 0
    tgs = 1

class Drive:
    """A drive's settings (all of them may change between steps)."""
    type: DriveType
    stiffness: float
    damping: float
    max_force: float
    target_position: float
    target_velocity: float
    max_impulse: float
    def __init__(self, type: Union[DriveType, str] = DriveType.force, stiffness: float = 0.0,
                 damping: float = 0.0, max_force: float = ..., target_position: float = 0.0,
                 target_velocity: float = 0.0, max_impulse: float = ...) -> None:
        """A drive; max_force and max_impulse default to inf (unlimited)."""

class JointFriction:
    """Joint friction: static and dynamic efforts and viscous friction."""
    static_effort: float
    dynamic_effort: float
    viscous: float
    def __init__(self, static_effort: float = 0.0, dynamic_effort: float = 0.0,
                 viscous: float = 0.0) -> None: ...
    def active(self) -> bool:
        """Whether any friction is set."""

class ActuatorEnvelope:
    """A DC-motor-like limit on a drive's effort (none while max_effort = 0)."""
    max_effort: float
    max_actuator_velocity: float
    speed_effort_gradient: float
    velocity_dependent_resistance: float
    def __init__(self, max_effort: float = 0.0, max_actuator_velocity: float = ...,
                 speed_effort_gradient: float = 0.0,
                 velocity_dependent_resistance: float = 0.0) -> None: ...
    def active(self) -> bool:
        """Whether the envelope limits the drive."""

class ActuatorKind(enum.Enum):
    """Which explicit actuator model (Isaac Lab's); docs/math/explicit_actuators.md."""
    none = 0
    ideal_pd = 1
    dc_motor = 2
    remotized_pd = 3

class ActuatorIntegration(enum.Enum):
    """Where an actuator's law is evaluated (docs/math/implicit_actuators.md)."""
    explicit = 0
    implicit = 1

class ExplicitActuator:
    """An explicit actuator of one joint; checked when given to Simulation.set_actuator."""
    kind: ActuatorKind
    stiffness: float
    damping: float
    effort_limit: float
    saturation_effort: float
    velocity_limit: float
    lookup: Vector
    delay: int
    integration: ActuatorIntegration
    def __init__(self, kind: Union[ActuatorKind, str] = ActuatorKind.ideal_pd, *,
                 stiffness: float = 0.0, damping: float = 0.0, effort_limit: float = ...,
                 saturation_effort: float = 0.0, velocity_limit: float = 0.0,
                 lookup: ArrayLike | None = None, delay: Int = 0,
                 integration: Union[ActuatorIntegration, str] = ActuatorIntegration.explicit
                 ) -> None: ...

def IdealPD(*, stiffness: float = 0.0, damping: float = 0.0, effort_limit: float = ...,
            delay: Int = 0,
            integration: Union[ActuatorIntegration, str] = ActuatorIntegration.explicit
            ) -> ExplicitActuator: ...
def DCMotor(*, stiffness: float = 0.0, damping: float = 0.0, effort_limit: float = ...,
            saturation_effort: float, velocity_limit: float, delay: Int = 0,
            integration: Union[ActuatorIntegration, str] = ActuatorIntegration.explicit
            ) -> ExplicitActuator: ...
def RemotizedPD(*, stiffness: float = 0.0, damping: float = 0.0, lookup: ArrayLike,
                effort_limit: float = ..., delay: Int = 0,
                integration: Union[ActuatorIntegration, str] = ActuatorIntegration.explicit
                ) -> ExplicitActuator: ...

class Compat(enum.Enum):
    """Whose defaults and step details a simulation follows."""
    none = 0
    physx = 1

class LinkParameters:
    """PhysX's per-link parameters (inert by default; PhysX's defaults with compat='physx')."""
    cfm_scale: float
    linear_damping: float
    angular_damping: float
    max_linear_velocity: float
    max_angular_velocity: float
    def __init__(self, cfm_scale: float = 0.0, linear_damping: float = 0.0,
                 angular_damping: float = 0.0, max_linear_velocity: float = ...,
                 max_angular_velocity: float = ...) -> None: ...

class StepGuard:
    """The step guard (docs/math/step_guard.md): a step that moves a joint more than
    max_joint_step or gains more energy than the joint forces' work is redone as 2, 4, ...
    sub-steps, at most max_substeps."""
    enabled: bool
    max_joint_step: float
    max_substeps: int
    energy_tolerance: float
    dissipation_share: float
    def __init__(self, enabled: bool = True, max_joint_step: float = 0.25,
                 max_substeps: Int = 64, energy_tolerance: float = 0.02,
                 dissipation_share: float = 0.15) -> None:
        """ValueError naming guard.max_joint_step (finite > 0), guard.max_substeps ([2, 4096]),
        guard.energy_tolerance ((0, 1]) or guard.dissipation_share ((0, 100])."""

class SimulationOptions:
    """Time step and solver settings."""
    dt: float
    solver: SolverType
    position_iterations: int
    velocity_iterations: int
    compat: Compat
    guard: StepGuard
    def __init__(self, dt: float = 1.0 / 60.0, solver: Union[str, SolverType] = "pgs",
                 position_iterations: Int = 4, velocity_iterations: Int = 1,
                 compat: Union[str, Compat] = "none") -> None:
        """ValueError for dt <= 0, position_iterations < 1 or velocity_iterations < 0."""

def row_kinds() -> list[dict]:
    """The row kinds besides drives, limits and friction (e.g. 'joint_spring'): each a dict of
    name, force (its output's name) and fields (name, default, doc)."""
def validate_options(options: SimulationOptions) -> None:
    """Raises ValueError naming the field and value for bad options."""

class Settings:
    """Every setting of a simulation as one value. Vectors write into the value; lists are
    copies: assign a whole list to change one."""
    options: SimulationOptions
    drives: list[Drive]
    lower_limit: Vector
    upper_limit: Vector
    max_joint_velocity: Vector
    friction: list[JointFriction]
    envelopes: list[ActuatorEnvelope]
    friction_coefficient: Vector
    revolute_wrap: list[str]
    drive_delay: list[int]
    actuators: list[ExplicitActuator]
    actuator_feedforward: Vector
    link_parameters: list[LinkParameters]
    mimic_joints: list[MimicJoint]
    ground: Ground
    contact: ContactOptions
    row_parameters: Vector
    """(nv, the row kinds' fields), kind after kind (row_kinds())."""
    @staticmethod
    def defaults(model: Model, options: SimulationOptions | None = None) -> Settings: ...
    def validate(self, model: Model) -> None:
        """ValueError with the message of the first setting a Simulation setter would refuse."""
    def copy(self) -> Settings: ...

class Link:
    """A link of a Model and its inbound joint (read-only)."""
    @property
    def name(self) -> str: ...
    @property
    def parent(self) -> int: ...
    @property
    def children(self) -> list[int]: ...
    @property
    def mass(self) -> float: ...
    @property
    def com(self) -> Vector: ...
    @property
    def inertia_com(self) -> Vector: ...
    @property
    def joint_name(self) -> str: ...
    @property
    def joint_type(self) -> JointType: ...
    @property
    def axis(self) -> Vector: ...
    @property
    def q_index(self) -> int: ...
    @property
    def v_index(self) -> int: ...
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def subtree_end(self) -> int: ...

class Model:
    """The immutable description of an articulation; one Model serves many simulations."""
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def gravity(self) -> Vector: ...
    @property
    def links(self) -> list[Link]: ...
    @property
    def armature(self) -> Vector: ...
    @property
    def lower_limit(self) -> Vector: ...
    @property
    def upper_limit(self) -> Vector: ...
    @property
    def effort_limit(self) -> Vector: ...
    @property
    def velocity_limit(self) -> Vector: ...
    @property
    def damping(self) -> Vector: ...
    @property
    def friction(self) -> Vector: ...
    @property
    def dof_link(self) -> list[int]: ...
    @property
    def dof_names(self) -> list[str]: ...
    @property
    def link_names(self) -> list[str]:
        """Link names in link order (depth-first preorder)."""
    @property
    def joint_names(self) -> list[str]:
        """Each link's inbound joint name in link order (the root's joint first)."""
    def floating_base(self) -> bool: ...
    def num_links(self) -> int: ...
    def link_index(self, name: str) -> int: ...
    def joint_link_index(self, joint_name: str) -> int: ...
    def dof_index(self, joint_name: str) -> int: ...
    def neutral_configuration(self) -> Vector: ...
    @property
    def shapes(self) -> list[CollisionShape]:
        """Collision shapes, grouped by link in link order."""
    @property
    def unsupported_shapes(self) -> list[str]:
        """Collision geometry contacts cannot use yet; a ground is refused while there is any."""

class ShapeType(enum.Enum):
    """The kind of a collision shape."""
    sphere = 0
    capsule = 1
    box = 2
    ellipsoid = 3
    cylinder = 4
    convex = 5

class Material:
    """Friction and restitution of a surface (a contact averages its two surfaces')."""
    static_friction: float
    dynamic_friction: float
    restitution: float
    def __init__(self, static_friction: float = 0.5, dynamic_friction: float = 0.5,
                 restitution: float = 0.0) -> None: ...

class CollisionShape:
    """A collision shape of a Model (read-only). size: sphere (r, 0, 0), capsule (r, half length,
    0) along the shape's z, box half extents, ellipsoid semi-axes, cylinder (r, half length, 0) along
    the shape's z; convex: unused (vertices holds the hull)."""
    @property
    def name(self) -> str: ...
    @property
    def link(self) -> int: ...
    @property
    def type(self) -> ShapeType: ...
    @property
    def size(self) -> Vector: ...
    @property
    def position(self) -> Vector: ...
    @property
    def rotation(self) -> Vector: ...
    @property
    def material(self) -> Material: ...
    @property
    def vertices(self) -> Vector:
        """convex: the hull's vertices in the shape frame (n, 3); else (0, 3)."""

class Ground:
    """The plane normal . x = height with a material; contacts when enabled."""
    enabled: bool
    height: float
    normal: Vector
    material: Material
    def __init__(self, enabled: bool = True, height: float = 0.0,
                 normal: ArrayLike = (0.0, 0.0, 1.0), material: Material = ...) -> None: ...

class ContactOptions:
    """PhysX 5.6.1's contact offset, rest offset (m) and bounce threshold (m/s), and whether the
    robot's own shapes collide."""
    contact_offset: float
    rest_offset: float
    bounce_threshold: float
    self_collision: bool
    def __init__(self, contact_offset: float = 0.02, rest_offset: float = 0.0,
                 bounce_threshold: float = 2.0, self_collision: bool = False) -> None: ...

class ContactReport:
    """One contact point of the last step (read-only)."""
    @property
    def link(self) -> int: ...
    @property
    def shape(self) -> int: ...
    @property
    def other_link(self) -> int: ...
    @property
    def other_shape(self) -> int: ...
    @property
    def position(self) -> Vector: ...
    @property
    def normal(self) -> Vector: ...
    @property
    def separation(self) -> float: ...
    @property
    def normal_impulse(self) -> float: ...
    @property
    def friction_impulse(self) -> Vector: ...

class JointSpec:
    """The inbound joint of a link, as in URDF."""
    name: str
    type: JointType
    origin_xyz: ArrayLike
    origin_rpy: ArrayLike
    axis: ArrayLike
    armature: list[float]
    lower_limit: float
    upper_limit: float
    effort_limit: float
    velocity_limit: float
    damping: float
    friction: float
    def __init__(self) -> None: ...

class LinkSpec:
    """A link description for ModelBuilder."""
    name: str
    parent: str
    mass: float
    com: ArrayLike
    inertia: ArrayLike
    joint: JointSpec
    def __init__(self) -> None: ...

def fixed_joint(name: str, xyz: ArrayLike = ..., rpy: ArrayLike = ...) -> JointSpec: ...
def revolute_joint(name: str, axis: ArrayLike, xyz: ArrayLike = ...,
                   rpy: ArrayLike = ...) -> JointSpec: ...
def prismatic_joint(name: str, axis: ArrayLike, xyz: ArrayLike = ...,
                    rpy: ArrayLike = ...) -> JointSpec: ...
def spherical_joint(name: str, xyz: ArrayLike = ..., rpy: ArrayLike = ...) -> JointSpec: ...
def floating_joint(name: str) -> JointSpec: ...
def make_link(name: str, parent: str, mass: float, com: ArrayLike, inertia: ArrayLike,
              joint: JointSpec) -> LinkSpec:
    """A LinkSpec; parent '' for the root."""

class ModelBuilder:
    """Builds a Model from LinkSpecs, validating once."""
    def __init__(self) -> None: ...
    def set_gravity(self, gravity: ArrayLike) -> ModelBuilder: ...
    def add_link(self, link: LinkSpec) -> ModelBuilder: ...
    def build(self) -> Model:
        """Raises ModelError (a ValueError)."""

class Simulation:
    """One simulation of a Model: state, drives, joint settings and the last step's forces."""
    @overload
    def __init__(self, model: Model, options: SimulationOptions) -> None: ...
    @overload
    def __init__(self, model: Model, settings: Settings) -> None:
        """ValueError as set_settings."""
    @overload
    def __init__(self, model: Model, dt: float = 1.0 / 60.0, solver: Union[str, SolverType] = "pgs",
                 position_iterations: Int = 4, velocity_iterations: Int = 1,
                 compat: Union[str, Compat] = "none",
                 stiffness: Union[float, ArrayLike, None] = None,
                 damping: Union[float, ArrayLike, None] = None,
                 drive_type: Union[str, DriveType] = "force") -> None:
        """Given stiffness or damping (scalar: every revolute and prismatic dof; or (nv,)),
        those dofs get drives of drive_type; else no dof has a drive."""
    def joint(self, name: str) -> JointAccessor:
        """A live accessor of a joint; ValueError naming the nearest names if unknown."""
    def copy(self) -> Simulation: ...
    @property
    def model(self) -> Model: ...
    @property
    def options(self) -> SimulationOptions:
        """A copy; set_options changes them."""
    def set_options(self, options: SimulationOptions) -> None: ...
    @property
    def settings(self) -> Settings:
        """Every setting as one value (a copy)."""
    def set_settings(self, settings: Settings) -> None:
        """Replaces every setting; ValueError naming the first bad one (nothing changes then)."""
    @property
    def q(self) -> Vector:
        """Configuration (nq,), a read-only view."""
    @property
    def qd(self) -> Vector:
        """Joint velocities (nv,), a read-only view."""
    def set_q(self, q: ArrayLike) -> None: ...
    def set_qd(self, qd: ArrayLike) -> None: ...
    def set_base_state(self, position: ArrayLike | None = None,
                       orientation: ArrayLike | None = None,
                       linear_velocity: ArrayLike | None = None,
                       angular_velocity: ArrayLike | None = None) -> None:
        """A floating root's pose and velocity in world axes (orientation w, x, y, z)."""
    def base_state(self) -> dict[str, Vector]: ...
    @property
    def time(self) -> float: ...
    @property
    def step_count(self) -> int: ...
    @property
    def guard_substeps(self) -> int: ...
    @property
    def guard_triggers(self) -> int: ...
    @property
    def guard_exhausted(self) -> int: ...
    def reset_guard_counters(self) -> None: ...
    def set_applied_force(self, tau: ArrayLike) -> None: ...
    @property
    def applied_force(self) -> Vector: ...
    def set_drive(self, joint: Joint, drive: Drive) -> None: ...
    def drive(self, joint: Joint) -> Drive: ...
    def set_drive_target(self, joint: Joint, position: float, velocity: float = 0.0) -> None: ...
    def set_drive_targets(self, positions: ArrayLike, velocities: ArrayLike | None = None) -> None:
        """Every dof's targets (nv,) each; velocities default to 0."""
    def set_drive_gains(self, stiffness: ArrayLike, damping: ArrayLike,
                        type: Union[DriveType, str] = DriveType.force) -> None:
        """Every dof's stiffness and damping ((nv,) or a scalar)."""
    def set_joint_limits(self, joint: Joint, lower: float, upper: float) -> None: ...
    def lower_limit(self, joint: Joint) -> float: ...
    def upper_limit(self, joint: Joint) -> float: ...
    def set_joint_friction(self, joint: Joint, friction: JointFriction) -> None: ...
    def joint_friction(self, joint: Joint) -> JointFriction: ...
    def set_max_joint_velocity(self, joint: Joint, max_velocity: float) -> None: ...
    def set_friction_coefficient(self, joint: Joint, coefficient: float) -> None: ...
    def friction_coefficient(self, joint: Joint) -> float: ...
    def set_link_parameters(self, link: Union[str, Int], parameters: LinkParameters) -> None: ...
    def link_parameters(self, link: Union[str, Int]) -> LinkParameters: ...
    def set_ground(self, ground: Ground) -> None:
        """ValueError naming the field and value, or the first of Model.unsupported_shapes."""
    def ground(self) -> Ground: ...
    def set_contact_options(self, options: ContactOptions) -> None: ...
    def contact_options(self) -> ContactOptions: ...
    def contacts(self) -> list[ContactReport]:
        """The contact points of the last step."""
    def link_contact_force(self) -> Vector:
        """The ground's force on each link over the last step (num_links, 3), world axes, N."""
    def foot_contact_force(self, links: Union[str, Int, Sequence[Union[str, Int]]]) -> Vector:
        """The sum of link_contact_force over links (a foot's), world axes, N (3,)."""
    def max_joint_velocity(self, joint: Joint) -> float: ...
    def set_row_parameters(self, kind: str, joint: Joint, **fields: float) -> None:
        """A row kind's fields on a joint by keyword (row_kinds()), e.g.
        set_row_parameters('joint_spring', 'knee', stiffness=240.0, reference=0.1); the fields
        not given keep their values."""
    def row_parameters(self, kind: str, joint: Joint) -> dict[str, float]: ...
    def row_force(self, kind: str) -> Vector:
        """The force a row kind applied on each dof in the last step (nv,), a copy."""
    def set_actuator_envelope(self, joint: Joint, envelope: ActuatorEnvelope) -> None: ...
    def actuator_envelope(self, joint: Joint) -> ActuatorEnvelope: ...
    def set_actuator(self, joint: Joint, actuator: ExplicitActuator) -> None:
        """ValueError beside a drive whose type is not 'none'; empties the delay history."""
    def actuator(self, joint: Joint) -> ExplicitActuator: ...
    def clear_actuator(self, joint: Joint) -> None: ...
    def set_actuator_feedforward(self, joint: Joint, effort: float) -> None: ...
    def reset_actuator_history(self) -> None: ...
    def set_drive_delay(self, joint: Joint, delay: Int) -> None:
        """The joint's drive uses the targets set delay steps earlier (0..100000; 0: none);
        empties its history. ValueError without a drive of type force or acceleration."""
    def drive_delay(self, joint: Joint) -> int: ...
    def reset_drive_delay_history(self) -> None: ...
    def set_revolute_wrap(self, joint: Joint, wrap: Literal['wrapped', 'unwrapped']) -> None:
        """PhysX's eREVOLUTE (q back into [-2 pi, 2 pi] after each step) or eREVOLUTE_UNWRAPPED."""
    def revolute_wrap(self, joint: Joint) -> str: ...
    def add_mimic_joint(self, follower: Joint, leader: Joint, gear_ratio: float,
                        offset: float = 0.0, natural_frequency: float = 0.0,
                        damping_ratio: float = 0.0) -> None:
        """q[follower] + gear_ratio q[leader] + offset = 0; soft when both last two are > 0."""
    def clear_mimic_joints(self) -> None: ...
    def mimic_joints(self) -> list[MimicJoint]: ...
    @property
    def actuator_force(self) -> Vector: ...
    @property
    def drive_force(self) -> Vector: ...
    @property
    def limit_force(self) -> Vector: ...
    @property
    def friction_force(self) -> Vector: ...
    @property
    def velocity_limit_force(self) -> Vector: ...
    def step(self, count: Int = 1) -> None:
        """Advances count steps (0 <= count < 2**31, GIL released); DivergenceError on a
        non-finite step; Ctrl-C: KeyboardInterrupt at a whole step."""
    def step_control(self, target_position: ArrayLike, target_velocity: ArrayLike = 0.0,
                     substeps: Int = 1, targets: str = "hold") -> None:
        """One control step: substeps (1..10**6) physics steps with the targets ((nv,) or a
        scalar) held ('hold') or interpolated from the previous ones ('linear': sub-step j uses
        prev + j/substeps (new - prev)); GIL released, Ctrl-C acts between control steps.
        DivergenceError names the sub-step. docs/math/control_step.md."""
    # Kinematics and dynamics at the current q and qd; every result a new array (a copy).
    # Spatial vectors [angular; linear]; frame 'world_aligned' (default) or 'local'.
    def link_pose(self, link: Union[str, Int]) -> tuple[Vector, Vector]:
        """(R (3, 3), p (3,)): the link's axes and origin in the world."""
    def frame_position(self, link: Union[str, Int], point: ArrayLike) -> Vector: ...
    def frame_velocity(self, link: Union[str, Int], point: ArrayLike | None = None,
                       frame: Union[str, ReferenceFrame] = "world_aligned") -> Vector: ...
    def jacobian(self, link: Union[str, Int], point: ArrayLike | None = None,
                 frame: Union[str, ReferenceFrame] = "world_aligned") -> Vector:
        """(6, nv); J qd = frame_velocity(link, point, frame)."""
    def jacobian_dot_times_qd(self, link: Union[str, Int], point: ArrayLike | None = None,
                              frame: Union[str, ReferenceFrame] = "world_aligned") -> Vector:
        """(6,): classical acceleration at qdd = 0 (world_aligned) or spatial (local)."""
    def mass_matrix(self) -> Vector: ...
    def bias_forces(self) -> Vector:
        """b = C qd + g: M qdd + b = tau in featherdrive's qd. MuJoCo's qfrc_bias only on a
        fixed base: with a floating root MuJoCo's qvel = A qd; see mujoco_qfrc_bias."""
    def mujoco_qfrc_bias(self) -> Vector:
        """MuJoCo's qfrc_bias (nv,): A (b - M A^T c) with a floating root, A = [0 R; 1 0],
        c = [R (w x v); 0]; bias_forces on a fixed base (docs/conventions.md)."""
    def gravity_forces(self) -> Vector: ...
    def inverse_dynamics(self, qdd: ArrayLike) -> Vector: ...
    def forward_dynamics(self, tau: ArrayLike) -> Vector:
        """qdd = M^-1 (tau - b) (ABA) at the current state; rigid bodies and armature only."""
    def center_of_mass(self) -> Vector: ...
    def center_of_mass_velocity(self) -> Vector: ...
    def center_of_mass_jacobian(self) -> Vector: ...

def set_drive_targets(sim: Simulation, positions: ArrayLike, velocities: ArrayLike) -> None: ...
def set_drive_gains(sim: Simulation, stiffness: ArrayLike, damping: ArrayLike,
                    type: Union[DriveType, str] = DriveType.force) -> None: ...

class JointAccessor:
    """One joint of a Simulation (Simulation.joint(name)), read and written at call time.
    One-dof joints give floats; multi-dof joints arrays (values) or lists (settings)."""
    @property
    def name(self) -> str: ...
    @property
    def type(self) -> JointType: ...
    @property
    def dof(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def link(self) -> int: ...
    @property
    def q(self) -> Union[float, Vector]: ...
    @property
    def qd(self) -> Union[float, Vector]: ...
    @property
    def drive_force(self) -> Union[float, Vector]: ...
    @property
    def limit_force(self) -> Union[float, Vector]: ...
    @property
    def friction_force(self) -> Union[float, Vector]: ...
    @property
    def applied_force(self) -> Union[float, Vector]: ...
    drive: Drive
    limits: tuple[float, float]
    friction: JointFriction
    max_velocity: float
    def row_parameters(self, kind: str) -> Union[dict[str, float], list[dict[str, float]]]: ...
    def set_row_parameters(self, kind: str, **fields: float) -> None:
        """A row kind's fields by keyword on every dof of the joint."""
    def row_force(self, kind: str) -> Union[float, list[float]]: ...
    def set_target(self, position: float, velocity: float = 0.0) -> None:
        """ValueError if the joint has no drive."""

class ReferenceFrame(enum.Enum):
    local = ...
    world_aligned = ...

# The same queries at a given state (q checked as Simulation.set_q checks it; new arrays).
def link_pose(model: Model, q: ArrayLike, link: Union[str, Int]) -> tuple[Vector, Vector]: ...
def frame_position(model: Model, q: ArrayLike, link: Union[str, Int],
                   point: ArrayLike) -> Vector: ...
def frame_velocity(model: Model, q: ArrayLike, qd: ArrayLike, link: Union[str, Int],
                   point: ArrayLike | None = None,
                   frame: Union[str, ReferenceFrame] = "world_aligned") -> Vector: ...
def jacobian(model: Model, q: ArrayLike, link: Union[str, Int], point: ArrayLike | None = None,
             frame: Union[str, ReferenceFrame] = "world_aligned") -> Vector: ...
def jacobian_dot_times_qd(model: Model, q: ArrayLike, qd: ArrayLike, link: Union[str, Int],
                          point: ArrayLike | None = None,
                          frame: Union[str, ReferenceFrame] = "world_aligned") -> Vector: ...
def mass_matrix(model: Model, q: ArrayLike) -> Vector: ...
def bias_forces(model: Model, q: ArrayLike, qd: ArrayLike) -> Vector: ...
def gravity_forces(model: Model, q: ArrayLike) -> Vector: ...
def inverse_dynamics(model: Model, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Vector: ...
def forward_dynamics(model: Model, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> Vector:
    """qdd = M^-1 (tau - b) (ABA); tau (nv,) finite; rigid bodies and armature only."""
def mujoco_qfrc_bias(model: Model, q: ArrayLike, qd: ArrayLike) -> Vector:
    """MuJoCo's qfrc_bias at (q, qd): bias_forces in MuJoCo's velocities (docs/conventions.md)."""
def center_of_mass(model: Model, q: ArrayLike) -> Vector: ...
def center_of_mass_velocity(model: Model, q: ArrayLike, qd: ArrayLike) -> Vector: ...
def center_of_mass_jacobian(model: Model, q: ArrayLike) -> Vector: ...

EnvIds = Union[None, Int, Sequence[Int], npt.NDArray[np.integer]]

class Batch:
    """N environments of one robot stepped together on all cores: in SIMD lanes, in groups of
    the environments that share dt, solver, iteration counts, compat, mimic dofs and shape
    links (the same bits for any group, lane, width, batch size and threads, within 1e-12 of
    each stepped alone); one whose settings the lanes refuse bit-identical to stepping it alone.
    States are read-only (N, n) views of the batch's arrays. Setters take env_ids (None: all;
    distinct indices in [0, N)) and values as a scalar, one row for every environment named or
    (k, n), one row each."""
    num_threads: int
    lanes: bool
    @property
    def isa(self) -> str:
        """The lanes' instruction set ('sse2', 'avx2', 'avx512'; ValueError for one this CPU
        lacks); set None for the default (the widest, FEATHERDRIVE_SIMD). Every width gives the
        same bits."""
    @isa.setter
    def isa(self, value: str | None) -> None: ...
    @property
    def step_path(self) -> str:
        """How the next step() runs: 'avx2 lanes' (one lane group), 'avx2 lanes: 2 groups (6, 2
        environments)', the environments in one-lane blocks (a group of one) counted last
        ('sse2 lanes (1 at one lane)', 'avx2 lanes: 2 groups (6, 1 environments; 1 at one
        lane)'), or 'scalar: ' and why (lanes off, FEATHERDRIVE_SIMD=scalar)."""
    def env_path(self, i: Int) -> str:
        """How the next step() runs environment i: 'avx2 lanes, group 1', 'sse2 lanes, group 1
        (one lane)' or 'scalar: ' and why."""
    @property
    def width(self) -> int:
        """Environments per vector of isa: 2, 4 or 8."""
    @property
    def step_count(self) -> list[int]: ...
    def divergences(self) -> dict[int, str]:
        """{environment: message} of the environments that stopped in the last step()."""
    def simulation(self, i: Int) -> Simulation:
        """Environment i as a Simulation of its own (a copy), unlike sim(i)."""
    @overload
    def __init__(self, model: Model, count: Int, dt: float = 1.0 / 60.0,
                 solver: Union[str, SolverType] = "pgs", position_iterations: Int = 4,
                 velocity_iterations: Int = 1,
                 compat: Union[str, Compat] = "none", stiffness: ArrayLike | None = None,
                 damping: ArrayLike | None = None,
                 drive_type: Union[str, DriveType] = "force") -> None: ...
    @overload
    def __init__(self, prototype: Simulation, count: Int) -> None: ...
    @overload
    def __init__(self, model: Model, count: Int, settings: Settings) -> None: ...
    def __len__(self) -> int: ...
    def size(self) -> int: ...
    @property
    def model(self) -> Model:
        """Environment 0's model (every environment's has its topology)."""
    def sim(self, i: Int) -> Simulation:
        """Environment i, live: its views are rows of the batch's; it shares the batch's lock."""
    def set_num_threads(self, threads: Int) -> None: ...
    def effective_num_threads(self) -> int: ...
    def set_options(self, options: SimulationOptions) -> None: ...
    @property
    def q(self) -> Vector:
        """(N, nq), a read-only view of the batch's storage."""
    @property
    def qd(self) -> Vector: ...
    @property
    def applied_force(self) -> Vector: ...
    @property
    def drive_force(self) -> Vector: ...
    @property
    def limit_force(self) -> Vector: ...
    @property
    def friction_force(self) -> Vector: ...
    @property
    def velocity_limit_force(self) -> Vector: ...
    @property
    def link_contact_force(self) -> Vector:
        """(N, num_links, 3): each environment's ground force on each link, last step (a copy)."""
    def contacts(self, i: Int) -> list[ContactReport]:
        """Environment i's contact points of the last step."""
    def set_q(self, values: ArrayLike, env_ids: EnvIds = None) -> None: ...
    def set_qd(self, values: ArrayLike, env_ids: EnvIds = None) -> None: ...
    def set_applied_force(self, values: ArrayLike, env_ids: EnvIds = None) -> None: ...
    def set_drive_targets(self, positions: ArrayLike, velocities: ArrayLike = 0.0,
                          env_ids: EnvIds = None) -> None: ...
    def set_drive_gains(self, stiffness: ArrayLike, damping: ArrayLike,
                        type: Union[DriveType, str] = DriveType.force,
                        env_ids: EnvIds = None) -> None: ...
    def set_drive(self, joint: str, drive: Drive) -> None: ...
    def set_actuator(self, joint: Joint, actuator: ExplicitActuator,
                     env_ids: ArrayLike | None = None) -> None:
        """The same actuator on one joint of the copies env_ids (None: all); all or nothing."""
    def reset(self, env_ids: EnvIds, q: ArrayLike | None = None,
              qd: ArrayLike | None = None) -> None:
        """q defaults to the batch's initial configuration, qd to 0; forces and clock 0."""
    def set_drive_delay(self, delays: ArrayLike, env_ids: EnvIds = None) -> None:
        """Drive delays in steps (whole numbers), a scalar, (nv,) or (k, nv); all or nothing."""
    def drive_delay(self) -> Vector: ...
    def set_armature(self, values: ArrayLike, env_ids: EnvIds = None) -> None: ...
    def set_joint_limits(self, lower: ArrayLike, upper: ArrayLike,
                         env_ids: EnvIds = None) -> None: ...
    def set_joint_friction(self, static: ArrayLike, dynamic: ArrayLike | None = None,
                           viscous: ArrayLike = 0.0, env_ids: EnvIds = None) -> None: ...
    def set_max_joint_velocity(self, values: ArrayLike, env_ids: EnvIds = None) -> None: ...
    def set_row_parameter(self, kind: str, field: str, values: ArrayLike,
                          env_ids: EnvIds = None) -> None:
        """One field of a row kind on env_ids (None: all): a scalar, (nv,) or (k, nv)."""
    def row_parameter(self, kind: str, field: str) -> Vector: ...
    def row_force(self, kind: str) -> Vector:
        """A row kind's forces of the last step (N, nv), a copy."""
    def set_link_mass(self, link: Union[str, Int], mass: ArrayLike, env_ids: EnvIds = None,
                      scale_inertia: bool = True) -> None: ...
    def set_link_com(self, link: Union[str, Int], com: ArrayLike,
                     env_ids: EnvIds = None) -> None: ...
    def set_gravity(self, gravity: ArrayLike, env_ids: EnvIds = None) -> None:
        """Gravity (3,) or (k, 3) of env_ids (None: all); the lanes take it per environment."""
    def gravity(self) -> Vector: ...
    def armature(self) -> Vector: ...
    def drive_gains(self) -> tuple[Vector, Vector]: ...
    def joint_limits(self) -> tuple[Vector, Vector]: ...
    def joint_friction(self) -> tuple[Vector, Vector, Vector]: ...
    def max_joint_velocity(self) -> Vector: ...
    def link_mass(self, link: Union[str, Int]) -> Vector: ...
    def link_com(self, link: Union[str, Int]) -> Vector: ...
    def observe(self, fields: Sequence[str]) -> Vector:
        """(N, k): the named fields side by side (q, qd, applied_force, drive_force,
        limit_force, friction_force, velocity_limit_force, target_position, target_velocity)."""
    def frame_positions(self, link: Union[str, Int], point: ArrayLike | None = None) -> Vector:
        """(N, 3) world positions of a point on a link in every environment."""
    def link_poses(self, link: Union[str, Int]) -> tuple[Vector, Vector]:
        """(R (N, 3, 3), p (N, 3)): Simulation.link_pose of every environment."""
    def jacobians(self, link: Union[str, Int], point: ArrayLike | None = None,
                  frame: Union[str, ReferenceFrame] = "world_aligned") -> Vector:
        """(N, 6, nv): Simulation.jacobian of every environment."""
    def mass_matrices(self) -> Vector:
        """(N, nv, nv): Simulation.mass_matrix of every environment (its own model)."""
    def bias_forces(self) -> Vector:
        """(N, nv): Simulation.bias_forces of every environment."""
    def step(self, count: Int = 1) -> None:
        """Steps every copy (0 <= count < 2**31, GIL released); DivergenceError names the lowest
        diverged copy; Ctrl-C: KeyboardInterrupt with every copy at the same whole step."""
    def step_control(self, target_position: ArrayLike, target_velocity: ArrayLike = 0.0,
                     substeps: Int = 1, targets: str = "hold") -> None:
        """Simulation.step_control for every copy: targets (N, nv), (nv,) for all copies or a
        scalar; a copy that diverges stops at its sub-step, the others make all of them."""

class UrdfEffort(enum.Enum):
    """What a URDF <limit effort> becomes (apply_urdf_effort_limits)."""
    none = 0
    max_force = 1
    effort_limit = 2

class UrdfOptions:
    fixed_base: bool
    gravity: ArrayLike
    effort: UrdfEffort
    def __init__(self, fixed_base: bool = True, gravity: ArrayLike = (0.0, 0.0, -9.81),
                 effort: Union[UrdfEffort, str] = UrdfEffort.none) -> None: ...

class MimicJoint:
    """q[follower] + gear_ratio q[leader] + offset = 0 (dofs); rigid unless both > 0."""
    follower: int
    leader: int
    gear_ratio: float
    offset: float
    natural_frequency: float
    damping_ratio: float

class UrdfMimic:
    joint: str
    leader: str
    multiplier: float
    offset: float

class UrdfRobot:
    """A robot read from URDF and its Model."""
    path: os.PathLike[str]
    input_files: list[os.PathLike[str]]
    name: str
    root_link: str
    root_joint: str
    options: UrdfOptions
    links: list[LinkSpec]
    joint_order: list[str]
    dof_order: list[int]
    @property
    def urdf_joint_names(self) -> list[str]:
        """Every <joint> in file order (fixed ones included)."""
    @property
    def dof_of_urdf_joint(self) -> npt.NDArray[np.int64]:
        """First dof of each urdf_joint_names entry; -1 for fixed joints."""
    @property
    def link_of_urdf_joint(self) -> npt.NDArray[np.int64]:
        """Model link of each joint's child (fixed: the link it was merged into)."""
    @property
    def urdf_joint_of_dof(self) -> npt.NDArray[np.int64]:
        """Index in urdf_joint_names of each dof's joint; -1 for a floating root's dofs."""
    mimics: list[UrdfMimic]
    warnings: list[str]
    effort_limits: dict[str, float]
    @property
    def ground(self) -> Ground | None:
        """The file's floor (an MJCF plane on the world body), or None."""
    @property
    def unsupported_shapes(self) -> list[str]: ...
    @property
    def model(self) -> Model: ...
    def rebuild(self) -> None: ...
    @property
    def merged(self) -> dict[str, tuple[str, Vector, Vector]]:
        """{link: (into, xyz, rotation)}: links merged through fixed joints (bind_view.cpp)."""

def apply_urdf_effort_limits(robot: UrdfRobot, sim: Simulation) -> None:
    """The URDF effort limits as max_force or effort_limit where none is set (robot.options)."""
def example_path(name: str) -> str:
    """The path of an example robot (examples/NAME, copied beside the module when it was built),
    e.g. example_path('arm7.urdf'); ValueError naming the ones there are."""
    ...

def load_urdf(path: PathLike, options: UrdfOptions = ...) -> UrdfRobot:
    """Raises InputError (a ValueError) naming the file."""
def parse_urdf(xml: str, name: str, options: UrdfOptions = ...) -> UrdfRobot: ...

class MjcfActuator:
    """An MJCF actuator on a hinge or slide and its featherdrive form."""
    name: str
    joint: str
    dof: int
    kind: str  # "motor" | "position" | "velocity"
    gear: float
    gain: float
    force_lower: float
    force_upper: float
    ctrl_lower: float
    ctrl_upper: float
    actuator: ExplicitActuator

class MjcfRobot(UrdfRobot):
    """A robot read from MJCF (docs/mujoco_bridge.md): q is MuJoCo's qpos."""
    actuators: list[MjcfActuator]
    @property
    def q0(self) -> Vector: ...

def apply_mjcf_actuators(robot: MjcfRobot, sim: Simulation) -> None:
    """Position and velocity actuators as explicit ideal_pd actuators; targets ctrl / gear."""
def load_mjcf(path: PathLike, options: UrdfOptions | None = None,
              fixed_base: bool | None = None) -> MjcfRobot:
    """Through MuJoCo 2.2.2's compiler; raises InputError (a ValueError) naming the file."""
def parse_mjcf(xml: str, name: str, options: UrdfOptions | None = None,
               fixed_base: bool | None = None) -> MjcfRobot: ...

class SineTarget:
    amplitude: float
    frequency: float
    phase: float
    offset: float
    def position(self, t: float) -> float: ...
    def velocity(self, t: float) -> float: ...

class DriveSpec:
    joint: str
    dof: int
    drive: Drive
    sine: SineTarget | None
    actuator: ExplicitActuator | None
    delay: int
    def target_at(self, t: float) -> tuple[float, float]: ...

class Scene:
    path: os.PathLike[str]
    model_path: os.PathLike[str]
    robot: UrdfRobot
    options: SimulationOptions
    steps: int
    q0: Vector
    qd0: Vector
    drives: list[DriveSpec]
    mimic: list[MimicJoint]
    @property
    def applied_forces(self) -> dict[str, float | SineTarget]: ...
    fit: FitSpec | None
    @property
    def model(self) -> Model: ...
    @property
    def ground(self) -> Ground:
        """The scene's ground (key ground, or the robot file's floor)."""
    @property
    def contact(self) -> ContactOptions: ...
    @property
    def feet(self) -> dict[str, list[str]]:
        """The scene's feet (key feet): {name: [link names]}."""

def load_scene(path: PathLike) -> Scene:
    """Raises InputError (a ValueError) naming the file, key and value."""
def parse_scene(text: str, path: PathLike) -> Scene: ...
def make_simulation(scene: Scene) -> Simulation: ...
def scene_settings(scene: Scene) -> Settings:
    """Every setting the scene gives; InputError naming the scene and the first bad value."""
def robot_settings(robot: UrdfRobot, options: SimulationOptions | None = None) -> Settings:
    """Defaults with options, the file's mimic rows, an MJCF file's actuators, the effort
    limits as robot.options.effort says."""
def apply_targets(scene: Scene, sim: Simulation, step_index: Int) -> None:
    """0 <= step_index <= 2**31 - 2."""
def sweep(scene: PathLike, grid: str | dict[str, ArrayLike], joint: str | None = None,
          client: object = None, num_threads: int = 0, chunk_size: int | None = None,
          objective: str = "rms") -> object:
    """featherdrive_sweep.sweep: tracking error over a grid of gains (a SweepResult); objective
    rms, overshoot, settling_time or max_force."""
MAX_INPUT_BYTES: int
def read_input_file(path: PathLike, what: str = "the file") -> bytes:
    """An input file's bytes as the commands read them (regular files of at most 64 MiB)."""
def view(source: PathLike | Scene | Simulation, out: PathLike | None = None, *,
         scene: PathLike | Scene | None = None, robot: UrdfRobot | PathLike | None = None,
         steps: int | None = None, packages: dict[str, PathLike] | None = None,
         marker: str | None = None, title: str | None = None) -> object:
    """featherdrive_view.view: the 3D viewer page of a scene, a CSV run or a Simulation (a
    ViewerPage, inline in Jupyter; docs/viewer.md)."""
def link_world_poses(model: Model, q: ArrayLike,
                     robot: UrdfRobot | None = None) -> tuple[list[str], Vector]:
    """(names, (T, L, 7) positions and quaternions (w, x, y, z)) at each row of q (T, nq);
    with robot, its links merged through fixed joints too."""


class CheckpointError(ValueError): ...

def save_checkpoint(sim: Simulation, path: str | os.PathLike[str]) -> None:
    """Writes the full simulation state atomically, bit-exact."""
def load_checkpoint(path: str | os.PathLike[str], sim: Simulation) -> None:
    """Restores a checkpoint into sim; CheckpointError (a ValueError) if it is not one of sim's
    model."""


# The MuJoCo bridge (docs/mujoco_bridge.md): gain translation and the MJCF export.
class MujocoIntegrator(enum.Enum):
    euler = ...
    implicit = ...

class DriveMapping(enum.Enum):
    translated = ...
    literal = ...

class DriveStepMap:
    """[q1, qd1] = A [q0, qd0] + B [x_T, v_T, f]."""
    A: npt.NDArray[np.float64]
    B: npt.NDArray[np.float64]

class MujocoDrive:
    kp: float
    kv: float
    damping: float
    armature: float
    ctrl_velocity_gain: float
    substeps: int
    interpolate_target: bool
    integrator: MujocoIntegrator
    def __init__(self) -> None: ...

class MapDistance:
    step_response: float
    poles: float
    steps: int

class MujocoTranslation:
    mujoco: MujocoDrive
    exact: bool
    reproducible: bool
    distance: MapDistance
    note: str

class PhysxTranslation:
    drive: Drive
    exact: bool
    reproducible: bool
    distance: MapDistance
    note: str

def physx_step_map(m: float, drive: Drive, options: SimulationOptions) -> DriveStepMap: ...
def mujoco_step_map(m: float, drive: MujocoDrive, dt: float) -> DriveStepMap: ...
def translate_to_mujoco(m: float, drive: Drive, options: SimulationOptions,
                        integrator: str | MujocoIntegrator = "euler",
                        keep_timestep: bool = False) -> MujocoTranslation: ...
def translate_to_physx(m: float, mujoco: MujocoDrive,
                       options: SimulationOptions) -> PhysxTranslation: ...
def effective_inertia(model: Model, q: ArrayLike) -> Vector:
    """1 / diag(M(q)^-1)."""
def model_to_mjcf(model: Model, dt: float) -> str: ...
def export_mjcf(sim: Simulation, drives: str | DriveMapping = "translated",
                integrator: str | MujocoIntegrator = "euler",
                keep_timestep: bool = False) -> dict[str, object]:
    """xml, timestep, substeps, notes, drives: [{joint, effective_inertia, mujoco, translation}]."""
def translate_mjcf_to_scene(mjcf: PathLike, scene_path: PathLike,
                            options: SimulationOptions = ...,
                            steps: Int = 240) -> dict[str, object]:
    """yaml (the scene's text; nothing is written), dt, integrator, notes, joints."""

# A scene's fit: section and the fit (docs/fitting.md; python/bind_fit.cpp, featherdrive_fit.py).
class FitParameter:
    quantity: str
    names: list[str]
    indices: list[int]
    lower: float
    upper: float
    shared: bool
    initial: list[float]
    key: str

class FitData:
    resample: str
    segment_steps: int
    qd_weight: float

class FitSpec:
    parameters: list[FitParameter]
    data: FitData
    def num_unknowns(self) -> int: ...

def fit(scene: Union[PathLike, Scene], data: PathLike, client: object = None,
        threads: Int | None = None, out: PathLike | None = None,
        chunks: Int | None = None, verbose: bool = False) -> object:
    """featherdrive_fit.fit: the scene's fit: parameters fitted to the log; a FitResult."""
def run_physx(sim: Simulation, steps: int, target_position: ArrayLike,
              harness_dirs: Sequence[PathLike]) -> tuple[Vector, Vector]:
    """(q, qd), (steps + 1, nv), from PhysX 5.6.1 itself (tests/physx's harness)."""
def run_mujoco(sim: Simulation, steps: int, target_position: ArrayLike,
               drives: str | DriveMapping = "translated",
               integrator: str | MujocoIntegrator = "euler") -> tuple[Vector, Vector]:
    """(q, qd), (steps + 1, nv), from MuJoCo 2.2.2 in-process (export_mjcf, the bridge)."""

def available_simd_isas() -> list[str]:
    """The instruction sets Batch.isa can take on this CPU, narrowest first ('sse2', ...)."""
def SimdBatch(prototype: Simulation, count: Int, isa: str | None = None) -> Batch:
    """Deprecated (DeprecationWarning): Batch(prototype, count) with isa; ValueError naming the
    setting when the lanes would not step it (Batch.step_path)."""

# ---- dof positions (model/dof_position.hpp) ----------------------------------------------------
def has_dof_position(model: Model, dof: Int) -> bool:
    """Whether the dof has a position of its own: a 1-dof joint's or a spherical joint's axis
    (not a floating root's)."""
def dof_positions(model: Model, q: ArrayLike, dofs: Sequence[Int] | None = None) -> Vector:
    """Each dof's position in q (nq,) or rows of q (T, nq), as the trajectory CSV's q:<dof>
    columns: q's entry for a 1-dof joint, PhysX's position of a spherical axis. dofs: default
    every dof with a position. Returns (len(dofs),) or (T, len(dofs))."""
def set_dof_positions(model: Model, q: ArrayLike, dofs: Sequence[Int] | None,
                      values: ArrayLike) -> Vector:
    """A copy of q with the dofs' positions set (the inverse of dof_positions)."""

# The stability check (docs/stability_check.md; python/bind_check.cpp).
class JointLaw(enum.Enum):
    """What acts on a dof in the one-joint step map."""
    none = 0
    drive = 1
    explicit_pd = 2
    implicit_pd = 3

class JointStability:
    joint: str
    dof: int
    axis: int
    """A spherical joint's axis 0, 1, 2; -1 for revolute and prismatic."""
    law: JointLaw
    mass: float
    """m = 1 / (M^-1)_jj, armature included."""
    stiffness_ratio: float
    """kp dt^2 / m (acceleration drives: kp dt^2)."""
    damping_ratio: float
    """kd / (2 sqrt(kp m)) (acceleration drives: kd / (2 sqrt(kp))); nan without kp."""
    rho: float
    """Spectral radius of the one-joint map of one physics step."""
    stable: bool
    substeps: int
    """For an unstable dof: the fewest physics steps per step of dt (0: none up to 1024)."""
    armature: float
    """For an unstable dof: the least armature to add (< 0: none)."""
    damping: float
    """For an unstable dof: the least damping to add (< 0: none)."""

class RobotStability:
    linear_rho: float
    linear_dofs: int
    linear_stable: bool
    trial_steps: int
    trial_bounded: bool
    trial_note: str
    substeps: int
    """For a diverging trial whose dofs are all stable: sub-steps that keep it bounded (0: none)."""

class StabilityReport:
    joints: list[JointStability]
    robot: RobotStability
    stable: bool
    verdict: str
    """'stable' or 'unstable: <joints and why>'."""

def check(scene: PathLike | Simulation, trial_steps: int | None = None) -> StabilityReport:
    """Will the run stay bounded? Per-dof step maps, a trial run, the smallest fixes.
    trial_steps: the trial's length (default: 2 s, 500 to 1000 steps; 0: none)."""
