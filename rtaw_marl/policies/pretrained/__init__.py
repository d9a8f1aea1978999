"""Pretrained RTAW policies shipped with the package (see :mod:`.registry`)."""
