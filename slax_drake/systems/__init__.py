"""Drake systems and diagrams: the station (robot, tool, shelf world, camera), the suction force element."""
