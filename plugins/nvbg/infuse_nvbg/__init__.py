"""Nonverbal behaviour generated from speech: a BML generator (see :mod:`infuse_nvbg.plugin`)."""
