"""One CommandError subclass per negative RetCode, with actionable messages."""
from __future__ import annotations

import pytest

from landscape import errors, ls
from landscape.errors import CommandError, LandscapeError, error_for_code, ret_name

NEGATIVE = [v.number for v in ls.RetCode.DESCRIPTOR.values if v.number < 0]


def test_every_negative_code_has_its_own_subclass() -> None:
    classes = [type(error_for_code("lock", c, "")) for c in NEGATIVE]
    assert len(set(classes)) == len(NEGATIVE) == 16
    for code, cls in zip(NEGATIVE, classes, strict=True):
        assert cls is not CommandError and issubclass(cls, CommandError) and issubclass(cls, LandscapeError)
        assert cls.code == code


@pytest.mark.parametrize("code,cls", [
    (ls.CMD_PARAM_ERR, errors.ParamError), (ls.CMD_PARAM_OUT_OF_RANGE_ERR, errors.ParamOutOfRangeError),
    (ls.CMD_WRONG_STATE_ERR, errors.WrongStateError), (ls.CMD_NOT_OWNER_ERR, errors.NotOwnerError),
    (ls.CMD_BUSY_ERR, errors.BusyError), (ls.CMD_NOT_CONNECTED_ERR, errors.NotConnectedError),
    (ls.CMD_NOT_IMPLEMENTED_ERR, errors.NotImplementedByDeviceError),
    (ls.CMD_UNSUPPORTED_ERR, errors.UnsupportedError), (ls.CMD_FAULT_ERR, errors.FaultError),
    (ls.CMD_UNKNOWN_CMD_ERR, errors.UnknownCommandError), (ls.CMD_NO_RESOURCES_ERR, errors.NoResourcesError),
    (ls.CMD_AUTH_ERR, errors.AuthError), (ls.CMD_SEQ_CONFLICT_ERR, errors.SeqConflictError),
])
def test_named_subclasses(code: int, cls: type) -> None:
    e = error_for_code("moveAbsolute", code, "speed_pct 120 is outside 0..100")
    assert type(e) is cls
    assert (e.command, e.ret_code, e.ret_msg, e.ret_name) == ("moveAbsolute", code, "speed_pct 120 is outside 0..100",
                                                              ls.RetCode.Name(code))
    assert str(e).startswith(f"moveAbsolute: {ls.RetCode.Name(code)}: speed_pct 120 is outside 0..100 (")


def test_unknown_code_keeps_base_class_and_a_name() -> None:
    e = error_for_code("lock", -99, "")
    assert type(e) is CommandError and ret_name(-99) == "RET_-99" and str(e) == "lock: RET_-99"


def test_every_way_a_motion_ends_has_its_advice() -> None:
    """The advice after a final alarm covers exactly the endings the schema declares (enum MotionEnd)."""
    from landscape.errors import ADVICE
    from landscape.notices import MOTION_END_REASONS

    assert set(ADVICE) == set(MOTION_END_REASONS) - {"complete"}
