"""curvlab: the desktop viewer of the curv library (PySide6 + pyvistaqt).

Layers: ``app.model`` (plain Python document, no Qt/VTK), ``app.controller`` (worker threads),
``app.views`` (Qt widgets and VTK viewports that only draw).
"""
