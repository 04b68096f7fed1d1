"""The task sets, named once: the paper's (set #1 and #2, the unseen tasks, the sparse
valve) and the planted-synergy test bed's. Plain names, no imports: presets, the report and
`discosyn --help` read them without JAX."""

TASK_SETS: dict[str, tuple[str, ...]] = {
    "set1": ("valve0", "valve1", "valve2", "valve3"),
    # set #2's valve is valve3 itself, under its own name: one task, one set of statistics
    "set2": ("dice", "valve3", "weight_pull", "screw"),
    "unseen": ("valve_cylinder", "valve_cw", "screw_topdown"),
    "sparse": ("valve_goal",),
    "planted": tuple(f"planted{n}" for n in range(4)),
    "planted_slack": tuple(f"planted_slack{n}" for n in range(4)),
    # three dense tasks and one that pays only once found (near its target; for an excursion):
    # what exploration does before it is
    "planted_found": ("planted0", "planted1", "planted2", "planted_found3"),
    "planted_reach": ("planted0", "planted1", "planted2", "planted_reach3"),
    "planted_far": ("planted0", "planted1", "planted2", "planted_far3"),
}
