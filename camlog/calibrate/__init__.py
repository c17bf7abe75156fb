"""Calibration of cameras from a log, one module per step: the flow and the report (the
maths is :mod:`processors.calibration`'s).

:mod:`.views` (the pass that detects the board in every frame), :mod:`.solving` (views
chosen, each camera and the stereo pair solved), :mod:`.rig_pairs` (a rig's pairs),
:mod:`.statistics` (their uncertainty and cross-validation), :mod:`.summary` (the typed
record of a run), :mod:`.evidence` (the annotated ``calibration.mcap``), :mod:`.report`,
:mod:`.figures` and :mod:`.markdown` (files, figures, ``report.md``), :mod:`.check`
(``--check`` of an existing calibration) and :mod:`.flow`, which runs them in order.
"""
