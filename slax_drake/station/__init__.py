"""The station as data and as plants: the typed station scenario, the robot description, the scene's objects as
Drake bodies and the depth/label renderer. Below both ``planning`` and ``systems``: every plant of the project
(the simulated station, the planning world, the checker's world, the controller plant) is built from here."""
