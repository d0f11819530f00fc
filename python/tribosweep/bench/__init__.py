"""The bench wing: work-precision charts, failure maps and model cost, reached by ``tribosweep bench``.

Nothing in the product imports this package; it needs the ``[bench]`` extra (scipy, numba,
matplotlib). Modules:

``scenes``        the physical situations measured (small batches of trajectories)
``runners``       one batch through the Rust core or a baseline, timed in this process
``analysis``      rows -> time at matched error, speed ratios, fastest method, friction laws
``charts``        the work-precision chart (a Figure) and the markdown summary
``workprecision`` measure everything and write CSV/JSON/PNG/markdown (:func:`run_work_precision`)
``failure``, ``status_map``, ``df_failure``, ``pd_failure``
                  where each integrator, the describing function and shooting fail, as maps
``model_cost``    cost and error of each analysis model over a sweep
``sweep_settings`` the Stribeck sweep's speed against its agreement, over transient rtol x transient_irregular_block
``ftle_settings``  the Lyapunov exponent's settings, judged on replicates along each attractor
``cycle_check``   what a run's periodic stop is worth against the shot orbit, and what the check costs
``reference``     the independent scipy oracle of the model (also the tests' reference)
``baselines``     the numba Dormand-Prince kernel and scipy batches the benches compare with
"""
