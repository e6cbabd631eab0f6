"""Campaigns: a case run (or analysed) for every combination of parameter values, on Dask.

variants: the parameters of the command line and the variants they make (grid or zip), each
    checked at load before anything runs. tasks: what a worker does with one variant (a run
    to its own history, or a complex eigenvalue analysis) and the summary row it returns.
campaign: the workers (an embedded LocalCluster of one-thread processes, or an existing
    scheduler), the variants' tasks, resume, the campaign's files sweep.csv and sweep.json.
"""
