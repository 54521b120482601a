# The Python package spinning_top (python/spinning_top): catkin_python_setup() puts it in the
# devel space; its compiled part, _core, is built by CMakeLists.txt (pybind11).
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["spinning_top"], package_dir={"": "python"}))
