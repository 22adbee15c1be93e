"""The model: xacro expansion and its checks (description), the TCP pose, the flattened export, their CLIs."""
