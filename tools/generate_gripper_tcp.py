"""Write config/gripper_tcp.yaml from expanded models: generate_gripper_tcp.py OUT.yaml LABEL=MODEL.urdf..."""
import sys

from ur3_ft_gripper_description.model import tcp

if __name__ == '__main__':
    if len(sys.argv) < 3 or not all('=' in a for a in sys.argv[2:]):
        sys.exit(__doc__.strip())
    sources = {}
    for arg in sys.argv[2:]:
        label, _, path = arg.partition('=')
        with open(path) as f:
            sources[label] = f.read()
    print(tcp.write_tcp_yaml(sys.argv[1], sources))
