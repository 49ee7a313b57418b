"""Offline tool for the wet-clutch TCU library (Shin & Choi friction model).

Subcommands (see ``wetclutch --help``): ``lut`` writes the firmware headers,
``reference`` evaluates the double-precision model, ``vectors`` writes golden
test vectors for the C tests.
"""
