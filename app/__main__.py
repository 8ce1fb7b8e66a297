"""``python -m app`` runs the viewer."""

from app.main import main

raise SystemExit(main())
