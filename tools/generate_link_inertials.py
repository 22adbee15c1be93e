"""Write config/link_inertials.yaml from config/robotiq_mass.yaml and the collision meshes.

Run in `bash tools/quickstart shell` (either robotiq variant: their meshes are
the same files). test/unit/test_inertials.py recomputes the table.
"""
import os
import sys

import rospkg
import yaml

from ur3_ft_gripper_description.model import inertials_from_meshes


def main():
    package = rospkg.RosPack().get_path('ur3_ft_gripper_description')
    with open(os.path.join(package, 'config', 'robotiq_mass.yaml')) as f:
        figures = yaml.safe_load(f)
    links, densities = inertials_from_meshes.compute_table(figures)
    out = os.path.join(package, 'config', 'link_inertials.yaml')
    inertials_from_meshes.write_yaml(out, links, densities)
    print('%s: %d links' % (out, len(links)))


if __name__ == '__main__':
    sys.exit(main())
