"""Generated NumPy-only model and controllers. DO NOT EDIT (python -m codegen)."""
