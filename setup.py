"""Packaging of gait_planner: an ament_python package (colcon) that pip installs as well."""

from glob import glob

from setuptools import find_packages, setup

package_name = "gait_planner"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*"]),
    package_data={package_name: ["py.typed", "ros/fastdds_profile.xml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/config", sorted(glob("config/*.yaml"))),
        ("share/" + package_name + "/config/scenes", sorted(glob("config/scenes/*.yaml"))),
    ],
    # Dependencies are pinned in requirements.txt (pip) and declared in package.xml (rosdep).
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="gait_planner maintainers",
    maintainer_email="gait-planner@example.com",
    description=(
        "Plans the half-cycle gait of a 3D seven-link walker by structure-preserving "
        "optimal control (DMOCC) with CasADi and IPOPT."
    ),
    license="Apache-2.0",
    python_requires=">=3.10",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "gait-planner = gait_planner.cli:main",
        ],
    },
)
