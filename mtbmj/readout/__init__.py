"""What a user reads from a run: the end of travel (``endtravel``: bumper, hard stop, rim
strikes, travel left; one definition for every command), the quick-look figure every drop and
roll writes (``quicklook``), a configuration's spring and damper curves (``curves``, ``mtbmj
curve``) and runs overlaid and differenced (``compare``, ``mtbmj compare``)."""
