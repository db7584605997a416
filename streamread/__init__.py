"""streamread."""
