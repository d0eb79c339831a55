"""roomba-bt: declarative behaviour-tree missions for iRobot Open Interface robots."""

__version__ = "0.1.0"
