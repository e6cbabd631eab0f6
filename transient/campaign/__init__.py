"""Campaigns: a case run (or analysed) for every combination of parameter values, on Dask.

variants: the parameters of the command line and the variants they make (grid or zip), named
    by their values, their count bounded before any is made. folder: --out checked to be a
    folder and held by one campaign at a time. outputs: what the campaign finds at each path
    it will write (absent, its own, the variant's own, or refused), and what --resume makes of
    it. tasks: what a worker does with one variant (a run to its own history, or a complex
    eigenvalue analysis) and the summary row it returns. campaign: the workers (an embedded
    LocalCluster of one-thread processes, or an existing scheduler), the variants' tasks, the
    campaign's files sweep.csv and sweep.json.
"""
