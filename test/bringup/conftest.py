"""test/bringup's tests of the cell's behaviour carry the `cell` mark (test/variant_scope.yaml)."""
from ur3_ft_gripper_testing.variant_scope import pytest_collection_modifyitems, pytest_configure  # noqa: F401 (hooks)
