"""Generated code (python -m codegen). DO NOT EDIT."""
