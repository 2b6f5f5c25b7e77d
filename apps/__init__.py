"""Applications built on the library packages.

The main job (``apps.main``), the paper's experiment (``apps.paper_experiment``) and the
bundled-design generator (``apps.make_designs``).
"""
