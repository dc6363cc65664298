"""Build the MuJoCo drop scene from the bundled MJCF and a configuration.

The tire is a MuJoCo soft contact calibrated to behave as the configured radial spring K (N/m)
and damper B (N s/m). MuJoCo's "direct" solref (-stiffness, -damping) is scaled by the contact's
inverse inertia A and its impedance d (docs/mujoco.md §2); with a constant impedance d (solimp
d0 = dwidth = d), ``diagexact`` and an elliptic cone, the contact force is
f = max(0, K pen + B pen_rate) when solref = (-K A (1-d), -B A (1-d)), up to a term d times the
other forces on the wheel, which the callback cancels (``DropScene.floor``). A is computed from
the compiled model (J M^-1 J^T at the tire's contact point), not assumed.
"""
from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from mtbmj import mjcf
from mtbmj.controllers import ContactFloor, installed
from mtbmj.compose import Setup

INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
}


@dataclass
class DropScene:
    model: mujoco.MjModel
    inverse_inertia: float  # A, 1/kg, at the tire contact along the normal
    sled_qpos: int
    sled_dof: int
    fork_qpos: int
    fork_dof: int
    tire_geom: int
    wheel_weight: float = 0.0  # N
    tire_values: tuple[float, float] = (0.0, 0.0)  # the law's (rate N/m, damping N s/m), set by set_tire

    @property
    def impedance(self) -> float:
        return float(self.model.geom_solimp[self.tire_geom, 0])

    def set_tire(self, rate: float, damping: float, callback=None) -> None:
        """Calibrated solref for a radial spring ``rate`` (N/m) and damper ``damping`` (N s/m);
        ``callback``'s contact correction (:meth:`floor`) follows."""
        scale = self.inverse_inertia * (1.0 - self.impedance)
        self.model.geom_solref[self.tire_geom] = (-rate * scale, -damping * scale)
        self.tire_values = (rate, damping)
        if callback is not None and hasattr(callback, "set_tire"):
            callback.set_tire(rate, damping)

    def floor(self) -> ContactFloor:
        """The correction that makes the contact the Kelvin-Voigt law exactly (its impedance
        stays in the force otherwise: ``controllers.tire.ContactFloor``), at the current values."""
        d = self.impedance
        rate, damping = self.tire_values
        return ContactFloor(factor=d / (1.0 - d), wheel_weight=self.wheel_weight, rate=rate, damping=damping)


def contact_inverse_inertia(model: mujoco.MjModel, geom: str = "tire") -> float:
    """J M^-1 J^T for the vertical direction at the lowest point of the tire geom, at qpos0."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    g = model.geom(geom)
    point = data.geom_xpos[g.id] - np.array([0.0, 0.0, model.geom_size[g.id, 0]])
    jacp = np.zeros((3, model.nv))
    mujoco.mj_jac(model, data, jacp, None, point, int(model.geom_bodyid[g.id]))
    jz = jacp[2].copy()
    minv_j = np.zeros(model.nv)
    mujoco.mj_solveM(model, data, minv_j.reshape(1, -1), jz.reshape(1, -1))
    return float(jz @ minv_j)


def build(setup: Setup, scene: str = "drop_scene.xml") -> DropScene:
    """Compile the drop scene with the configuration's masses, geometry, gravity and solver."""
    spec = mujoco.MjSpec.from_file(str(mjcf.path(scene)))
    spec.option.timestep = setup.timestep
    spec.option.integrator = INTEGRATORS[setup.integrator]
    spec.option.gravity = [0.0, 0.0, -setup.gravity]
    sled = spec.body("sled")
    sled.mass = setup.body_mass
    # At qpos = 0 the tread just touches the floor: the sled's zero and the paper's t = 0.
    sled.pos = [0.0, 0.0, setup.tire_radius + setup.fork_length]
    lower = spec.body("fork_lower")
    lower.mass = setup.wheel_mass
    lower.pos = [0.0, 0.0, -setup.fork_length]
    spec.geom("tire").size = [setup.tire_radius, 0.0, 0.0]
    # The control callback is process-global and compiling runs the model forward: a Python
    # callback installed by someone else would fire on a half-built model (MuJoCo then fails
    # with "Python exception raised"). Compile and calibrate with no callback installed.
    with installed(None):
        model = spec.compile()
        inverse_inertia = contact_inverse_inertia(model)
    sled_joint = model.joint("sled")
    fork_joint = model.joint("fork")
    scene_obj = DropScene(
        model=model,
        inverse_inertia=inverse_inertia,
        sled_qpos=int(sled_joint.qposadr[0]),
        sled_dof=int(sled_joint.dofadr[0]),
        fork_qpos=int(fork_joint.qposadr[0]),
        fork_dof=int(fork_joint.dofadr[0]),
        tire_geom=int(model.geom("tire").id),
        wheel_weight=setup.wheel_mass * setup.gravity,
    )
    first = setup.tire.values(0)
    scene_obj.set_tire(first.rate, first.damping)
    return scene_obj
