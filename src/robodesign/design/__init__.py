"""Design search: the immutable ``Problem``, its search space, the staged solve pipeline, the evaluator and the
optimizer plugin loop (``Study``, ``optimize``)."""
