"""A second robot that is not ours: plain rclpy nodes, no dxboard code in them (issue 28)."""
