"""A pytest plugin (-p pytest_shards): with VKRAY_TEST_SHARD=K/N a run keeps the K-th of N runs of
consecutive tests, in collection order (so that a module's fixtures serve the tests beside them). A
long test file is then N ctest tests, each within the suite's budget (tests/CMakeLists.txt,
python_shards)."""
import os


def pytest_collection_modifyitems(config, items):
    shard = os.environ.get("VKRAY_TEST_SHARD")
    if not shard:
        return
    index, count = (int(part) for part in shard.split("/"))
    kept = items[len(items) * index // count:len(items) * (index + 1) // count]
    config.hook.pytest_deselected(items=[item for item in items if item not in kept])
    items[:] = kept
