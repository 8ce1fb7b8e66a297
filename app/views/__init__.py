"""Qt widgets and VTK viewports; they draw the model and forward user edits to it."""
