"""The float32 certificate's committed results (``results/<robot>.json``) and how the
generated headers and MODEL.md state them; the certifier itself is the C backend's
(:mod:`codegen.backends.c.certify`: it reads the C the backend prints), run by
``python -m codegen.backends.c.certify``."""
