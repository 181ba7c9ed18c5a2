"""Self-collision of an arm from its URDF: Pinocchio's collision model, checked by coal.

The geometry is the URDF's collision elements (``pin.buildGeomFromUrdf(..., pin.COLLISION)``)
on the full model (fingers at their neutral value). All pairs are checked except:
- those an SRDF disables (``pin.removeCollisionPairs``), the SRDF given or the one
  example-robot-data keeps beside its URDF (``../srdf/<name>.srdf``); otherwise
- pairs on the same or on adjacent joints (parent and child), and pairs already touching at
  the reference configuration (links that touch by design, such as a gripper on its flange).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from comgrasp_pin._paths import example_robot_data_dir
from comgrasp_pin.errors import CollisionError
from comgrasp_pin.robot import RobotModel


class SelfCollision:
    """Answers "does the arm hit itself at q?" for the arm joints of ``robot``.

    Attributes:
        model: the full Pinocchio model; geom_model, geom_data its collision geometry.
        srdf: the SRDF used, or None (adjacent and touching pairs removed instead).
        n_pairs: number of collision pairs checked.
    """

    def __init__(
        self, robot: RobotModel, srdf: str | Path | None = None, q_ref: np.ndarray | None = None
    ):
        if robot.urdf_path is None:
            raise CollisionError("the robot has no URDF path: its collision model is unknown")
        urdf = Path(robot.urdf_path)
        dirs = [*robot.package_dirs, str(urdf.parent), str(example_robot_data_dir().parent)]
        self.model = pin.buildModelFromUrdf(str(urdf))
        try:
            self.geom_model = pin.buildGeomFromUrdf(
                self.model, str(urdf), pin.COLLISION, package_dirs=dirs
            )
        except (ValueError, RuntimeError) as exc:
            raise CollisionError(f"cannot build the collision model of {urdf}: {exc}") from None
        if len(self.geom_model.geometryObjects) < 2:
            raise CollisionError(f"{urdf} has fewer than two collision geometries")
        self._q_index = np.array([self.model.idx_qs[self.model.getJointId(n)]
                                  for n in robot.joint_names])  # fmt: skip
        self._q_full = pin.neutral(self.model)
        self.geom_model.addAllCollisionPairs()
        self.srdf = _find_srdf(urdf) if srdf is None else Path(srdf)
        if self.srdf is not None:
            if not self.srdf.is_file():
                raise CollisionError(f"SRDF not found: {self.srdf}")
            pin.removeCollisionPairs(self.model, self.geom_model, str(self.srdf))
        else:
            self._remove_adjacent()
        self.geom_data = self.geom_model.createData()
        if self.srdf is None:
            q = (
                np.clip(np.zeros(robot.nq), robot.q_lower, robot.q_upper)
                if q_ref is None
                else q_ref
            )
            self._remove_touching(q)
        self.n_pairs = len(self.geom_model.collisionPairs)

    def full_q(self, q: np.ndarray) -> np.ndarray:
        """The full model's configuration for arm configuration ``q`` (n,)."""
        qf = self._q_full.copy()
        qf[self._q_index] = q
        return qf

    def colliding_pairs(self, q: np.ndarray) -> list[tuple[str, str]]:
        """Names of the geometry pairs in collision at arm configuration ``q``."""
        pin.computeCollisions(self.model, pin.Data(self.model), self.geom_model,
                              self.geom_data, self.full_q(q), False)  # fmt: skip
        out = []
        for k, res in enumerate(self.geom_data.collisionResults):
            if res.isCollision():
                p = self.geom_model.collisionPairs[k]
                names = (self.geom_model.geometryObjects[i].name for i in (p.first, p.second))
                out.append(tuple(names))
        return out

    def in_collision(self, q: np.ndarray) -> bool:
        """True if any checked pair collides at arm configuration ``q``."""
        return pin.computeCollisions(self.model, pin.Data(self.model), self.geom_model,
                                     self.geom_data, self.full_q(q), True)  # fmt: skip

    def _remove_adjacent(self) -> None:
        gm = self.geom_model
        parents = self.model.parents
        pairs = [(p.first, p.second) for p in gm.collisionPairs]  # copies: removal shifts
        for first, second in pairs:
            a = gm.geometryObjects[first].parentJoint
            b = gm.geometryObjects[second].parentJoint
            if a == b or parents[a] == b or parents[b] == a:
                gm.removeCollisionPair(pin.CollisionPair(first, second))

    def _remove_touching(self, q: np.ndarray) -> None:
        pin.computeCollisions(self.model, pin.Data(self.model), self.geom_model,
                              self.geom_data, self.full_q(q), False)  # fmt: skip
        pairs = self.geom_model.collisionPairs
        results = self.geom_data.collisionResults
        touching = [(p.first, p.second) for p, r in zip(pairs, results) if r.isCollision()]
        for first, second in touching:
            self.geom_model.removeCollisionPair(pin.CollisionPair(first, second))
        self.geom_data = self.geom_model.createData()


def _find_srdf(urdf: Path) -> Path | None:
    """example-robot-data's SRDF for ``urdf`` (robots/<x>_description/srdf/<name>.srdf)."""
    candidate = urdf.parent.parent / "srdf" / f"{urdf.stem}.srdf"
    return candidate if candidate.is_file() else None
