r"""Experiments: the config schema and loading (:mod:`.schema`,
:mod:`.config`), the module registry (:mod:`.registry`), training
(:mod:`.train`), equal-budget sweeps (:mod:`.sweep`) and the demo
(:mod:`.demo`). Importing this package imports nothing heavy."""
