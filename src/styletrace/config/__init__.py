"""The `stylized` integrator's configuration: one declaration per property (declare.py), their
parsing into `Settings` (settings.py), and the estimator registry (estimator_registry.py: name,
forms, what n means, builder)."""
