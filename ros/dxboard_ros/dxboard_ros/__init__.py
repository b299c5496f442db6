"""dxboard's daemon as a ROS 2 node (the ``dxboard`` executable of this package)."""
