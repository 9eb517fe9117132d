"""ROS 1 bags (format 2.0): the file and its records, decoded into the ROS 2 shapes bridges read."""
