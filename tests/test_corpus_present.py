from corpus_data import CORPUS, labels, require_corpus


def test_corpus_is_present_and_labelled():
    require_corpus()
    assert len(labels()) >= 220, f"expected the labelled corpus at {CORPUS}"
