"""RCON Sensor widgets: Image, Accelerometer, Gyroscope, Magnetometer, Camera, Multi-Touch teleop."""
