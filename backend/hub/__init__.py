"""The hub's wiring: ``start.py`` builds the services once per process, ``services.py``
holds them (the ``Hub``), ``work.py`` runs their background work. Only ``backend/app.py``
and the features' wiring import it; routes take typed dependencies
(``backend/api/deps.py``)."""
