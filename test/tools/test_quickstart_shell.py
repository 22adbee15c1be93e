"""tools/quickstart shell keeps the workspace's Python whatever the user's ~/.bashrc puts first on PATH.

Run by tools/quickstart test after the catkin tests, on the workspace it set up
(UR3_FT_GRIPPER_WS, UR3_FT_GRIPPER_UPSTREAM as given to it).
"""
import os
import subprocess
import sys
import venv

PKG_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
QUICKSTART = os.path.join(PKG_DIR, 'tools', 'quickstart')


def home_whose_bashrc_puts_a_python_without_rospy_first(tmp_path):
    bare = tmp_path / 'bare-python'
    venv.EnvBuilder(system_site_packages=False, with_pip=False).create(str(bare))
    python3 = bare / 'bin' / 'python3'
    lacks = subprocess.run([str(python3), '-c', 'import rospy'], stderr=subprocess.DEVNULL)
    assert lacks.returncode != 0, '%s imports rospy: it cannot stand for a conda or pyenv python' % python3
    home = tmp_path / 'home'
    home.mkdir()
    (home / '.bashrc').write_text('export PATH=%s:$PATH\n' % (bare / 'bin'))
    return home, python3


def quickstart_shell(home, command):
    env = dict(os.environ, HOME=str(home))
    return subprocess.run(['bash', QUICKSTART, 'shell', command], env=env, stdin=subprocess.DEVNULL,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                          timeout=900)


def test_a_rostest_runs_inside_the_shell_despite_the_bashrc(tmp_path):
    home, bare = home_whose_bashrc_puts_a_python_without_rospy_first(tmp_path)
    run = quickstart_shell(home, 'echo "python3=$(command -v python3)"; rostest ur3_ft_gripper_description tf_chain.test')
    assert run.returncode == 0, run.stdout[-3000:]
    python3 = [line for line in run.stdout.splitlines() if line.startswith('python3=')]
    assert python3 and python3[0] != 'python3=%s' % bare, run.stdout[-3000:]
    summary = run.stdout.split('SUMMARY')[-1]
    assert 'RESULT: SUCCESS' in summary and '* ERRORS: 0' in summary and '* FAILURES: 0' in summary, summary


def test_the_bashrc_alone_would_have_broken_the_nodes(tmp_path):
    # The same .bashrc in a plain interactive shell: python3 is the bare one.
    home, bare = home_whose_bashrc_puts_a_python_without_rospy_first(tmp_path)
    run = subprocess.run(['bash', '-i', '-c', 'command -v python3'], env=dict(os.environ, HOME=str(home)),
                         stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                         universal_newlines=True)
    assert run.stdout.strip().splitlines()[-1] == str(bare)


if __name__ == '__main__':
    sys.exit(subprocess.call([sys.executable, '-m', 'pytest', __file__]))
