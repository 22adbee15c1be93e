"""Debian's joint_state_publisher_gui, with QSlider.setValue taking the floats it passes."""
import runpy
import sys

try:
    from python_qt_binding.QtWidgets import QSlider
except ImportError:  # Debian 13 has no python_qt_binding: its joint_state_publisher_gui imports PyQt5 itself
    from PyQt5.QtWidgets import QSlider

DEBIAN_EXECUTABLE = '/usr/lib/joint_state_publisher_gui/joint_state_publisher_gui'

_set_integer_value = QSlider.setValue


def _set_rounded_value(slider, value):
    _set_integer_value(slider, int(round(value)))


if __name__ == '__main__':
    QSlider.setValue = _set_rounded_value
    sys.argv[0] = DEBIAN_EXECUTABLE
    runpy.run_path(DEBIAN_EXECUTABLE, run_name='__main__')
