"""Calibration of cameras from a log, one module per step: the flow and the report (the
maths is :mod:`processors.calibration`'s).

:mod:`.views` (the pass that detects the board in every frame), :mod:`.instants` (the
solver's views, numbered once), :mod:`.solving` (every camera, the rig and the board poses
solved: a :class:`~.solving.RigSolution` of :class:`~.solving.CalibratedCamera`),
:mod:`.rig_pairs` (a rig's pairs), :mod:`.statistics` (each camera's uncertainty and
cross-validation, computed when the flow asks), :mod:`.summary` (the typed
record of a run), :mod:`.evidence` (the annotated ``calibration.mcap``), :mod:`.report`,
:mod:`.figures` and :mod:`.markdown` (files, figures, ``report.md``), :mod:`.check`
(``--check`` of an existing calibration) and :mod:`.flow`, which runs them in order.
"""
