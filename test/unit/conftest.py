"""The unit tests' fixtures; what the tests import by name lives in ur3_ft_gripper_testing.model.

Nothing is imported from here by name: test/unit and test/physics run in one pytest session, where
two modules named conftest cannot both be imported.
"""
import pytest

from ur3_ft_gripper_testing.model import configured, expand
from ur3_ft_gripper_testing.variant_scope import pytest_collection_modifyitems, pytest_configure  # noqa: F401 (hooks)


@pytest.fixture
def expand_model():
    return expand


@pytest.fixture(scope='session')
def configured_model():
    """Expands each (ur_type, ft_sensor, gripper[, prefix]) once per test session."""
    return configured


@pytest.fixture(scope='session')
def default_model():
    return expand()

