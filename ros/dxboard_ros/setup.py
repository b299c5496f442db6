"""The dxboard_ros package: ament_python, around the dxboard distribution (pip)."""

from glob import glob

from setuptools import setup

PACKAGE = "dxboard_ros"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="dxboard maintainers",
    maintainer_email="dxboard@example.org",
    description="dxboard's daemon as a ROS 2 node, with its launch, params and analyzers files",
    license="MIT",
    entry_points={"console_scripts": [f"dxboard = {PACKAGE}.node:main"]},
)
