"""Colours and sizes the views share."""

PANE_COLOURS = ("#2a7ae2", "#e2762a", "#2aa14a", "#a23ad6", "#707070")
"""Frame colour of pane A, B, C, D and the difference pane: the active pane's group in the Inspect
panel has the same colour, so it is clear which pane its estimator and range belong to."""
