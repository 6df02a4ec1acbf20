"""Long work as jobs: a persistent store, job kinds, executors and the runner that drives them.

A job kind (sweep; optimize later) says how a job's spec splits into tasks of points, runs a
task in a worker, and assembles the result. The runner and the store know nothing of kinds
beyond that interface, so a new kind is one new module registered in `kinds`.
"""
