"""Robustness campaigns: thousands of closed-loop runs over the uncertainty box on Dask.

``python -m runtime campaign`` (:mod:`runtime.commands.campaign`). One module per job:

* :mod:`~runtime.campaign.spec`: the campaign file (TOML), checked field by field, and its hash;
* :mod:`~runtime.campaign.sampling`: each run's parameters from (campaign seed, run index);
* :mod:`~runtime.campaign.runner`: one run through the generated C (what a worker executes);
* :mod:`~runtime.campaign.store`: Parquet parts written atomically, resume, the spec record;
* :mod:`~runtime.campaign.execution`: the Dask client, chunked tasks, progress bar;
* :mod:`~runtime.campaign.prediction`: the boundary the sampled-data analysis predicts;
* :mod:`~runtime.campaign.summary` and :mod:`~runtime.campaign.plots`: what the user reads.

See docs/CAMPAIGN.md.
"""
