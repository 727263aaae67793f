"""MuJoCo as an independent plant: the engine on the MJCF the toolchain writes from the
robot's description (``modeling.mjcf_export``), behind the closed loop's ``Plant``
protocol (:mod:`runtime.mujoco.plant`), and the map between the engine's coordinates and
the derived model's (:mod:`runtime.mujoco.coordinates`)."""
