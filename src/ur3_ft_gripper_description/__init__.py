"""UR3 + Robotiq FT 300 + Robotiq 2F-140: model expansion and simulated devices."""
