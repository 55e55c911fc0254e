"""Package data: the built-in model's weights (``builtin.safetensors``, when
a version ships them; see :mod:`satagraph.io.weights`)."""
