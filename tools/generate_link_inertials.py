"""Write config/link_inertials.yaml from config/robotiq_mass.yaml and the collision meshes.

Run in `bash tools/quickstart shell` (either robotiq variant: their meshes are
the same files). test/unit/test_inertials.py recomputes the table.
"""
import os
import sys

import rospkg

from ur3_ft_gripper_description import kinematics
from ur3_ft_gripper_description.model import description, export, inertials


def expanded(**options):
    return kinematics.Model(description.to_xml(description.expand_model(export.model_mappings(**options))))


def main():
    package = rospkg.RosPack().get_path('ur3_ft_gripper_description')
    with open(os.path.join(package, 'config', 'robotiq_mass.yaml')) as f:
        import yaml
        figures = yaml.safe_load(f)
    links, densities = inertials.distribute(
        expanded(), expanded(ft_sensor=False), figures, export.resolve_uri)
    out = os.path.join(package, 'config', 'link_inertials.yaml')
    inertials.write_yaml(out, links, densities)
    print('%s: %d links' % (out, len(links)))


if __name__ == '__main__':
    sys.exit(main())
