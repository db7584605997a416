"""The bundled networks' loading (``onnxmodel.load_session``): errors a user can act on."""

from __future__ import annotations

from pathlib import Path

import pytest

from streamread.digits import DigitReader
from streamread.errors import DependencyError, InputError
from streamread.bore_net import BoreNet


def _stopper_net(path: Path) -> BoreNet:
    return BoreNet(path, indicator="stopper")


@pytest.mark.parametrize("network,what", [(DigitReader, "digit model"), (BoreNet, "meniscus model"),
                                          (_stopper_net, "stopper model")])
def test_a_missing_or_broken_model_is_a_clear_error(network, what: str, tmp_path: Path) -> None:  # noqa: ANN001
    with pytest.raises(DependencyError, match=what):
        network(tmp_path / "none.onnx")
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"not a model")
    with pytest.raises(InputError, match=f"{what}.*an ONNX model onnxruntime can load"):
        network(bad)
