"""The station as data and as plants: the typed station scenario, the robot description, the scene's objects as
Drake bodies and the depth/label renderer. Below both ``planning`` and ``systems``: every plant of the project
(the simulated station, the planning world, the checker's world, the controller plant) is built from here."""

# The default station file (repository-relative). Here, not in scenario.py, so that command-line parsers can name
# it without importing Drake.
DEFAULT_STATION = "sim_configs/station_sim_shelf.yaml"
