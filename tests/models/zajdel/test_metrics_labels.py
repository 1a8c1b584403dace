"""The partition scores refuse what is not a label array, naming it."""

import numpy as np
import pytest

from dbn.errors import DBNError, NonFiniteError, ShapeError
from models.zajdel.metrics import num_objects, pairwise_prf, partition_accuracy


@pytest.mark.parametrize(("pred", "true", "error", "needle"), [
    ([0, np.nan], [0, 1], NonFiniteError, "pred[1] = nan is not a label"),
    ([0, 1], np.array([0, None], dtype=object), DBNError, "true[1] = None is not a label"),
    ([0, 1, 1], [0, 1], ShapeError, "pred has 3 observations, true has 2"),
    ([[0, 1]], [[0, 1]], ShapeError, "pred: expected a 1-D label array"),
    (5, [0], ShapeError, "pred: expected a 1-D label array (num_obs,), got shape ()"),
])  # fmt: skip
def test_scores_refuse_what_is_not_a_label_array(pred, true, error, needle) -> None:
    """A NaN label matched any label (pred [0, nan] against [0, 1] scored 1.0), a table
    was flattened, a length mismatch was a bare ValueError."""
    for score in (partition_accuracy, pairwise_prf):
        with pytest.raises(error) as exc:
            score(pred, true)
        assert needle in str(exc.value)


def test_labels_of_any_kind_still_score() -> None:
    """Only equality matters: strings or floats of whole numbers are labels."""
    assert partition_accuracy(["a", "b", "b"], [3.0, 1.0, 1.0]) == 1.0
    assert pairwise_prf(np.array(["x", "x"]), [0, 1]) == (0.0, 1.0, 0.0)
    assert num_objects(["a", "b", "a"]) == 2
    with pytest.raises(ShapeError):
        num_objects(None)
