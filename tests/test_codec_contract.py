"""Every registered codec keeps the codec contract (tests/codec_contract.py)."""

import pytest

from mzc.codecs import BUILT_IN, codec_names, get_codec

from codec_contract import FIXTURE_NAME, REPO, check_codec, fixture_names


@pytest.mark.parametrize("name", codec_names())
def test_codec_keeps_the_contract(name):
    check_codec(get_codec(name))


@pytest.mark.parametrize("name", BUILT_IN)
def test_built_in_codec_has_a_spec_page_and_a_fixture_of_every_major_it_reads(name):
    codec = get_codec(name)
    assert codec.spec and (REPO / codec.spec).is_file()
    majors = {int(FIXTURE_NAME.match(n)["major"]) for n in fixture_names(codec.kind)}
    assert majors == set(range(codec.oldest_major, codec.version[0] + 1))
    assert codec.summary and codec.extension.startswith(".")
