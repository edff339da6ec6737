"""The built-in BML behaviour handlers of infuse, registered like any third-party plugin."""
