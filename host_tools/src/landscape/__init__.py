"""LandScape over CAN: supervisor library and command-line tool for landscaped controllers.

    from landscape import Supervisor, BusSpec
    with Supervisor.open_bus(BusSpec("slcan", "/dev/pts/3")) as sup:
        print(sup.get_motion_control_state().result)
"""
from ._generated import landscape_pb2 as ls
from .bus import BusSpec, open_bus
from .errors import (
    AddressInUseError,
    AlarmError,
    ArgumentError,
    BusError,
    BusyError,
    CommandError,
    ControllerTimeoutError,
    DeviceTimeoutError,
    FaultError,
    GenericCommandError,
    LandscapeError,
    LinkLostError,
    NoResourcesError,
    NotConnectedError,
    NotImplementedByDeviceError,
    NotOwnerError,
    ParamError,
    ParamOutOfRangeError,
    ProtocolError,
    UnknownCommandError,
    UnsupportedError,
    VersionMismatchCommandError,
    VersionMismatchError,
    WrongStateError,
    error_for_code,
)
from .paths import PathFile, PathFileError, build_path_load_requests, load_path_file, parse_path_text
from .registry import COMMANDS, PROTOCOL_VERSION, SCHEMA_HASH, Command, build_request, lookup
from .retval import RetVal
from .supervisor import ConnectResult, Supervisor, mismatch_message, notice_data

__all__ = [
    "ls", "BusSpec", "open_bus", "Supervisor", "RetVal", "ConnectResult", "mismatch_message", "notice_data",
    "COMMANDS", "Command", "PROTOCOL_VERSION", "SCHEMA_HASH", "build_request", "lookup", "error_for_code",
    "LandscapeError", "BusError", "LinkLostError", "ControllerTimeoutError", "VersionMismatchError", "ProtocolError",
    "AlarmError", "ArgumentError", "CommandError", "GenericCommandError", "ParamError", "ParamOutOfRangeError",
    "WrongStateError", "NotOwnerError", "AddressInUseError", "BusyError", "DeviceTimeoutError", "NotConnectedError",
    "NotImplementedByDeviceError", "UnsupportedError", "VersionMismatchCommandError", "FaultError",
    "UnknownCommandError", "NoResourcesError",
    "PathFile", "PathFileError", "build_path_load_requests", "load_path_file", "parse_path_text",
]
__version__ = "0.1.0"
