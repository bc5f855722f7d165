"""Force-field tables (TOML) of dnabraid, installed as the package ``dnabraid.forcefields``.

The files are read with ``importlib.resources`` by :mod:`dnabraid.forcefield`; this module
only makes the directory a regular package, which editable installs need to map it.
"""
