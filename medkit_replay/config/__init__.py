"""Config files in, typed values out: upstream's YAML files read as yaml-cpp 0.7 reads them.

Readers only: files are opened read-only and nothing is ever written or created.
"""
