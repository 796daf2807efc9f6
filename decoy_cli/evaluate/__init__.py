"""`decoy evaluate`: replay many rounds in parallel and measure the replay's fidelity.

* settings.py: the options that decide a round's result, the fixed grids, the cache keys;
* job.py: the per-file and per-round jobs a worker runs, and the compact `RoundRecord`;
* backends.py: local worker processes, or an existing Dask cluster;
* cache.py: one file per round result in the output folder, so a run resumes;
* runner.py: inputs to files to rounds to results, failures recorded, nothing printed;
* tables.py: the aggregate tables next to the DECOY paper's numbers;
* figures.py, report.py: the figures, the CSV/JSON tables and report.md.

Nothing is imported here, so a worker that imports the job module pays only for what it uses.
"""
