"""The one cache of loaded models and its freshness rule (SQLite and PostgreSQL): a reference
is served the version it names now; an answer of the store is reused only while younger
than the age asked; live sessions and predictions share it."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.synthetic import touch_arff
from touchbench.app.errors import NotFoundError
from touchbench.app.schemas.datasets import ImportRequest
from touchbench.app.schemas.models import TrainRequest
from touchbench.app.schemas.references import parse_model_ref
from touchbench.app.services.datasets import import_file
from touchbench.app.services.model_cache import ModelCache
from touchbench.app.services.models import train
from touchbench.app.store.aliases import set_alias
from touchbench.app.store.database import Store
from touchbench.app.store.models import delete_model


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def two_versions(store: Store, tmp_path: Path) -> Store:
    """``mic`` versions 1 (nb) and 2 (j48)."""
    import_file(
        store,
        ImportRequest(file=touch_arff(tmp_path / "t.arff", n=30, with_place=False), name="touch"),
    )
    for classifier in ("nb", "j48"):
        train(store, TrainRequest(dataset="touch", classifier=classifier, name="mic"))
    return store


def test_a_reference_is_served_the_version_it_names_now(two_versions: Store) -> None:
    store, clock = two_versions, Clock()
    cache = ModelCache(4, clock=clock)
    info, model = cache.get(store, "mic")
    assert info.label == "mic@2" and cache.get(store, "mic")[1] is model  # loaded once
    assert cache.known("mic") == info.id and cache.known("nothing") is None
    set_alias(store, "mic@1", "champion")
    assert cache.get(store, "mic@champion")[0].label == "mic@1"
    set_alias(store, "mic@2", "champion")
    assert cache.get(store, "mic@champion")[1] is model  # moved: the one loaded

    # an answer younger than max_age is reused; older, the store is asked again
    set_alias(store, "mic@1", "champion")
    assert cache.version(store, "mic@champion", max_age=1.0).label == "mic@2"
    clock.now += 1.0
    assert cache.version(store, "mic@champion", max_age=1.0).label == "mic@1"

    delete_model(store, "mic@2")
    assert cache.get(store, "mic")[0].label == "mic@1"  # never the deleted one
    with pytest.raises(NotFoundError, match="no version 2"):
        cache.get(store, "mic@2")
    cache.forget(info.id)
    assert cache.known(str(info.id)) is None


def test_the_cache_keeps_at_most_its_size(two_versions: Store) -> None:
    cache = ModelCache(1)
    first = cache.get(two_versions, "mic@1")[1]
    cache.get(two_versions, "mic@2")
    assert cache.get(two_versions, "mic@1")[1] is not first  # dropped, loaded again


def test_references_are_read_by_one_grammar() -> None:
    cases = {
        "mic": ("mic", None, None, None, False),
        "mic@3": ("mic", "version", 3, None, True),
        "mic@007": ("mic", "version", 7, None, True),
        "mic@0": ("mic", "version", None, None, True),
        "mic@latest": ("mic", "latest", None, None, False),
        "mic@champion": ("mic", "alias", None, "champion", False),
        "old@name@2": ("old@name", "version", 2, None, True),
        "17": ("17", None, None, None, True),
    }
    for text, (name, kind, version, alias, pinned) in cases.items():
        ref = parse_model_ref(text)
        assert (ref.name, ref.kind, ref.version, ref.alias, ref.pinned) == (
            name,
            kind,
            version,
            alias,
            pinned,
        ), text
    assert parse_model_ref(17).id == 17 and parse_model_ref("99999999999").id is None
