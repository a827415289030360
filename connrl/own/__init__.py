"""Your own Gymnasium task: the thesis's learners as an SB3-style API (``connrl.make_agent``, ``connrl.load``,
``connrl.evaluate``; ``api.py``), their files (``files.py``), settings files and tuning (``settings.py``,
``tune.py``), callbacks (``callbacks.py``) and the ``connrl train`` / ``evaluate`` / ``tune`` commands (``cli.py``,
``cli_evaluate.py``, ``cli_tune.py``), curves (``plots.py``) and the API reference (``reference.py``)."""
