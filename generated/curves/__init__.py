"""Generated curve modules, one per boundary curve. Never edit by hand."""
