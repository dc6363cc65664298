"""Measured data in: the readers of what comes from the world (SST and travel-CSV telemetry, dyno,
tire, terrain and sled records) and the signal tools every rig, fit and check reads them with
(rider metrics, pedal-bob reading, a sled record's time zero, noise, smoothing and peaks). Nothing
here imports a rig. Import the module you need: ``from mtbmj.measured.telemetry import read_sst``."""
