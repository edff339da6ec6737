"""Example third-party mapper for infuse: ``c_<canonical>`` joint names, the rest by the default mapper."""
