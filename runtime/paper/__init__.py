"""The paper's experiments and analyses on its differential drive (Roy et al. 2017).

Written around the default generated code (``wmr_``, five coordinates q = (x_c, y_c, θ, θ_r,
θ_l)): Drishti, or any ``[lumped]``/``[physical]`` robot file, which shares its structure
and runs on that code with its own numbers. The generic runtime (``runtime.robot_*``,
``runtime.closed_loop``) runs any generated robot; this package is the paper robot's own:

``simulate`` (closed loop with the C controllers, encoders, odometry and the RK4 plant of
``csrc/wmr_sim.c`` via ``sim_library``), ``references`` (circle and lawn mower),
``payload_schedule``, ``controller_config`` with ``nominal_check`` and ``sampled_loop``
(refusing a configuration predicted unstable), ``stability`` and ``stability_check`` (the
sampled-data stability analysis and its simulated check), ``reproduce`` (the paper's
experiments) with ``reproduction_tables``, ``reproduction_verdicts`` (the claims and the
stability bounds), ``reproduction_report`` and ``figures`` (their metrics, report and
figures), and ``handwritten`` (the paper's equations typed by hand, the reference of the
cross-check and the benchmarks, with ``csrc/hand_model.c``). ``csrc/fuzz_driver.c``
drives the ``wmr_`` controllers under sanitizers (tests/test_firmware_sanitizers.py).

No imports here: each module is imported on its own.
"""
