"""docs/reference/scenarios.md's [[failure]] tables are the fault catalog's, not a stale copy."""

from silbridge.shm import fault_catalog
from silbridge.tools.docs import failure_tables


def test_the_page_matches_the_catalog():
    page = failure_tables.PAGE.read_text()
    assert failure_tables.render(page) == page, \
        "stale: run python -m silbridge.tools.docs.failure_tables"


def test_every_unit_type_and_parameter_is_on_the_page():
    text = failure_tables.markdown()
    for u in fault_catalog.UNITS:
        assert f'`unit = "{u.name}"`' in text
        for t in u.types:
            assert f'`type = "{t.name}"`' in text
            for p in t.params:
                assert f"| `{t.name}` | `{p.name}` |" in text
