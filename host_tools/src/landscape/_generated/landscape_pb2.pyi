from google.protobuf import descriptor_pb2 as _descriptor_pb2
from google.protobuf.internal import containers as _containers
from google.protobuf.internal import enum_type_wrapper as _enum_type_wrapper
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from typing import ClassVar as _ClassVar, Iterable as _Iterable, Mapping as _Mapping, Optional as _Optional, Union as _Union

ABSENT_MEANS_FIELD_NUMBER: _ClassVar[int]
ABSOLUTE_DATA: OffsetType
ALARM: NoticeKind
ALARM_RSVP: NoticeKind
ANGULAR_ACCEL: AccelType
ANGULAR_SPEED: SpeedType
AUTH_CHALLENGE_TTL_MS: AuthParam
AUTH_HEARTBEAT_MAC_BITS: AuthParam
AUTH_KEY_BYTES: AuthParam
AUTH_MAC_BYTES: AuthParam
AUTH_NONCE_BYTES: AuthParam
AUTH_PARAM_NONE: AuthParam
AUTH_POLICY_NONE: AuthPolicy
AUTH_SIGNED: AuthPolicy
AUTH_UNSIGNED: AuthPolicy
AUX_NAMED_EVENT: EventId
BASE_CARTESIAN_FRAME: ReferenceFrame
CB_ALARM: CallbackType
CB_ALARM_RSVP: CallbackType
CB_EVENT: CallbackType
CB_EVENT_RSVP: CallbackType
CENTIMETERS: LinearUnit
CIRCULAR_MOTION: MotionType
CMD_AUTH_ERR: RetCode
CMD_BUSY_ERR: RetCode
CMD_ERR: RetCode
CMD_EXEC_OK: RetCode
CMD_FAULT_ERR: RetCode
CMD_FIELD_NUMBER: _ClassVar[int]
CMD_NOT_CONNECTED_ERR: RetCode
CMD_NOT_IMPLEMENTED_ERR: RetCode
CMD_NOT_OWNER_ERR: RetCode
CMD_NO_RESOURCES_ERR: RetCode
CMD_PARAM_ERR: RetCode
CMD_PARAM_OUT_OF_RANGE_ERR: RetCode
CMD_SEQ_CONFLICT_ERR: RetCode
CMD_STARTED_OK: RetCode
CMD_TIMEOUT_ERR: RetCode
CMD_UNKNOWN_CMD_ERR: RetCode
CMD_UNSUPPORTED_ERR: RetCode
CMD_VERSION_MISMATCH_ERR: RetCode
CMD_WRONG_STATE_ERR: RetCode
DEFAULT_DEVICE_ADDRESS: NodeAddress
DEFAULT_HOST_ADDRESS: NodeAddress
DEGREES: AngularUnit
DESCRIPTOR: _descriptor.FileDescriptor
DISCONNECT_CONFIGURED: DisconnectAction
DISCONNECT_STOP: DisconnectAction
DISCONNECT_STOP_DEACTIVATE: DisconnectAction
DISCONNECT_STOP_DEACTIVATE_RELEASE: DisconnectAction
END_ABORT: MotionEnd
END_AUX_FAILED: MotionEnd
END_COMPLETE: MotionEnd
END_DEACTIVATE: MotionEnd
END_DISCONNECT: MotionEnd
END_EMERGENCY: MotionEnd
END_FAULT: MotionEnd
END_OWNER_LOST: MotionEnd
END_RSVP_DECLINED: MotionEnd
END_SHUTDOWN: MotionEnd
EVENT: NoticeKind
EVENT_ID_NONE: EventId
EVENT_RSVP: NoticeKind
FEET: LinearUnit
FINAL_SUFFIX_FIELD_NUMBER: _ClassVar[int]
FUNCTIONAL_ALL_DEVICES: NodeAddress
HEARTBEAT_PERIOD_MAX_MS: HeartbeatPeriod
HEARTBEAT_PERIOD_MIN_MS: HeartbeatPeriod
HEARTBEAT_PERIOD_NONE: HeartbeatPeriod
HOME_FAILED: HomeState
HOME_HOMED: HomeState
HOME_HOMING: HomeState
HOME_NOT_HOMED: HomeState
HOST_ADDRESS_POOL_LAST: NodeAddress
IDLE: State
INCHES: LinearUnit
ISOTP_BLOCK_SIZE: IsotpParam
ISOTP_FUNCTIONAL_BASE: IsotpId
ISOTP_ID_NONE: IsotpId
ISOTP_MAX_MESSAGE_BYTES: IsotpParam
ISOTP_N_TIMEOUT_MS: IsotpParam
ISOTP_PADDING_BYTE: IsotpParam
ISOTP_PHYSICAL_BASE: IsotpId
ISOTP_ST_MIN: IsotpParam
JOINT_FRAME: ReferenceFrame
JOINT_MOTION: MotionType
LINEAR_ACCEL: AccelType
LINEAR_SPEED: SpeedType
LOCKED: State
METERS: LinearUnit
MILLIMETERS: LinearUnit
MOVING: State
NODE_NONE: NodeAddress
NOTICE_KEYS_FIELD_NUMBER: _ClassVar[int]
PAUSED: State
PERCENT_ACCEL: AccelType
PERCENT_SPEED: SpeedType
PROTOCOL_NONE: Protocol
PROTOCOL_VERSION: Protocol
RADIANS: AngularUnit
RELATIVE_DATA: OffsetType
REQUIRED_FIELD_NUMBER: _ClassVar[int]
RESTING: State
SI_PER_UNIT_FIELD_NUMBER: _ClassVar[int]
SLEW_MOTION: MotionType
STATE_NONE: State
STRAIGHT_MOTION: MotionType
SYMBOL_FIELD_NUMBER: _ClassVar[int]
TEXT_FIELD_NUMBER: _ClassVar[int]
TOOL_FRAME: ReferenceFrame
UNLOCKED: State
WORLD_CARTESIAN_FRAME: ReferenceFrame
absent_means: _descriptor.FieldDescriptor
alarmsSuppressed: EventId
cmd: _descriptor.FieldDescriptor
commandFailed: EventId
complyAborted: EventId
complyComplete: EventId
complyEnvelope: EventId
complyFailed: EventId
complyPanicStop: EventId
complyTimeout: EventId
dioSignal: EventId
dioSignalRsvpTimeout: EventId
dioSignalTimeout: EventId
driveEmcy: EventId
driveErrorCode: EventId
fault: EventId
final_suffix: _descriptor.FieldDescriptor
manualDeviceFound: EventId
manualDeviceLost: EventId
manualFrame: EventId
manualLimit: EventId
manualOverride: EventId
manualSwitch: EventId
moveAbsoluteAborted: EventId
moveAbsoluteComplete: EventId
moveAbsoluteFailed: EventId
moveArcAborted: EventId
moveArcComplete: EventId
moveArcFailed: EventId
moveReactAborted: EventId
moveReactComplete: EventId
moveReactEnvelope: EventId
moveReactFailed: EventId
moveReactPanicStop: EventId
moveReactTimeout: EventId
moveRelativeAborted: EventId
moveRelativeComplete: EventId
moveRelativeFailed: EventId
notice_keys: _descriptor.FieldDescriptor
ownerLost: EventId
pathMoveAborted: EventId
pathMoveComplete: EventId
pathMoveFailed: EventId
required: _descriptor.FieldDescriptor
si_per_unit: _descriptor.FieldDescriptor
slowedDown: EventId
symbol: _descriptor.FieldDescriptor
tag: EventId
text: _descriptor.FieldDescriptor

class AbortMotionReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class AbortMotionRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ActivateReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ActivateRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ActivateToolReq(_message.Message):
    __slots__ = ["bit_field", "tool_id"]
    BIT_FIELD_FIELD_NUMBER: _ClassVar[int]
    TOOL_ID_FIELD_NUMBER: _ClassVar[int]
    bit_field: int
    tool_id: str
    def __init__(self, tool_id: _Optional[str] = ..., bit_field: _Optional[int] = ...) -> None: ...

class ActivateToolRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ChallengeReq(_message.Message):
    __slots__ = ["host_nonce", "key_id"]
    HOST_NONCE_FIELD_NUMBER: _ClassVar[int]
    KEY_ID_FIELD_NUMBER: _ClassVar[int]
    host_nonce: bytes
    key_id: str
    def __init__(self, key_id: _Optional[str] = ..., host_nonce: _Optional[bytes] = ...) -> None: ...

class ChallengeRes(_message.Message):
    __slots__ = ["auth_policy", "device_nonce", "key_id"]
    AUTH_POLICY_FIELD_NUMBER: _ClassVar[int]
    DEVICE_NONCE_FIELD_NUMBER: _ClassVar[int]
    KEY_ID_FIELD_NUMBER: _ClassVar[int]
    auth_policy: AuthPolicy
    device_nonce: bytes
    key_id: str
    def __init__(self, device_nonce: _Optional[bytes] = ..., auth_policy: _Optional[_Union[AuthPolicy, str]] = ..., key_id: _Optional[str] = ...) -> None: ...

class CommandSpec(_message.Message):
    __slots__ = ["blocking", "host_timeout_ms", "name", "owner_only", "query", "seed_section", "states", "summary"]
    BLOCKING_FIELD_NUMBER: _ClassVar[int]
    HOST_TIMEOUT_MS_FIELD_NUMBER: _ClassVar[int]
    NAME_FIELD_NUMBER: _ClassVar[int]
    OWNER_ONLY_FIELD_NUMBER: _ClassVar[int]
    QUERY_FIELD_NUMBER: _ClassVar[int]
    SEED_SECTION_FIELD_NUMBER: _ClassVar[int]
    STATES_FIELD_NUMBER: _ClassVar[int]
    SUMMARY_FIELD_NUMBER: _ClassVar[int]
    blocking: bool
    host_timeout_ms: int
    name: str
    owner_only: bool
    query: bool
    seed_section: str
    states: _containers.RepeatedScalarFieldContainer[State]
    summary: str
    def __init__(self, name: _Optional[str] = ..., states: _Optional[_Iterable[_Union[State, str]]] = ..., blocking: bool = ..., owner_only: bool = ..., host_timeout_ms: _Optional[int] = ..., seed_section: _Optional[str] = ..., summary: _Optional[str] = ..., query: bool = ...) -> None: ...

class ComplyReq(_message.Message):
    __slots__ = ["compliance_speed_pct", "differential_gains", "envelope_max", "envelope_min", "max_timeout_s", "max_travel", "panic_stop_code", "proportional_gains", "sensor_type", "speed_pct", "thresholds"]
    COMPLIANCE_SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    DIFFERENTIAL_GAINS_FIELD_NUMBER: _ClassVar[int]
    ENVELOPE_MAX_FIELD_NUMBER: _ClassVar[int]
    ENVELOPE_MIN_FIELD_NUMBER: _ClassVar[int]
    MAX_TIMEOUT_S_FIELD_NUMBER: _ClassVar[int]
    MAX_TRAVEL_FIELD_NUMBER: _ClassVar[int]
    PANIC_STOP_CODE_FIELD_NUMBER: _ClassVar[int]
    PROPORTIONAL_GAINS_FIELD_NUMBER: _ClassVar[int]
    SENSOR_TYPE_FIELD_NUMBER: _ClassVar[int]
    SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    THRESHOLDS_FIELD_NUMBER: _ClassVar[int]
    compliance_speed_pct: float
    differential_gains: _containers.RepeatedScalarFieldContainer[float]
    envelope_max: _containers.RepeatedScalarFieldContainer[float]
    envelope_min: _containers.RepeatedScalarFieldContainer[float]
    max_timeout_s: float
    max_travel: _containers.RepeatedScalarFieldContainer[float]
    panic_stop_code: int
    proportional_gains: _containers.RepeatedScalarFieldContainer[float]
    sensor_type: str
    speed_pct: float
    thresholds: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, sensor_type: _Optional[str] = ..., thresholds: _Optional[_Iterable[float]] = ..., max_timeout_s: _Optional[float] = ..., panic_stop_code: _Optional[int] = ..., max_travel: _Optional[_Iterable[float]] = ..., proportional_gains: _Optional[_Iterable[float]] = ..., differential_gains: _Optional[_Iterable[float]] = ..., speed_pct: _Optional[float] = ..., compliance_speed_pct: _Optional[float] = ..., envelope_min: _Optional[_Iterable[float]] = ..., envelope_max: _Optional[_Iterable[float]] = ...) -> None: ...

class ComplyRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ConnectReq(_message.Message):
    __slots__ = ["client_name", "client_nonce", "disconnect_action", "heartbeat_period_ms", "host_nonce", "key_id", "protocol_version", "schema_hash"]
    CLIENT_NAME_FIELD_NUMBER: _ClassVar[int]
    CLIENT_NONCE_FIELD_NUMBER: _ClassVar[int]
    DISCONNECT_ACTION_FIELD_NUMBER: _ClassVar[int]
    HEARTBEAT_PERIOD_MS_FIELD_NUMBER: _ClassVar[int]
    HOST_NONCE_FIELD_NUMBER: _ClassVar[int]
    KEY_ID_FIELD_NUMBER: _ClassVar[int]
    PROTOCOL_VERSION_FIELD_NUMBER: _ClassVar[int]
    SCHEMA_HASH_FIELD_NUMBER: _ClassVar[int]
    client_name: str
    client_nonce: int
    disconnect_action: DisconnectAction
    heartbeat_period_ms: int
    host_nonce: bytes
    key_id: str
    protocol_version: int
    schema_hash: int
    def __init__(self, protocol_version: _Optional[int] = ..., schema_hash: _Optional[int] = ..., client_name: _Optional[str] = ..., heartbeat_period_ms: _Optional[int] = ..., disconnect_action: _Optional[_Union[DisconnectAction, str]] = ..., client_nonce: _Optional[int] = ..., key_id: _Optional[str] = ..., host_nonce: _Optional[bytes] = ...) -> None: ...

class ConnectRes(_message.Message):
    __slots__ = ["angular_unit", "auth_policy", "client_nonce", "device_name", "disconnect_action", "firmware_version", "heartbeat_timeout_ms", "heartbeat_token", "joint_count", "linear_unit", "owner", "protocol_version", "schema_hash", "session_epoch", "session_signed", "state"]
    ANGULAR_UNIT_FIELD_NUMBER: _ClassVar[int]
    AUTH_POLICY_FIELD_NUMBER: _ClassVar[int]
    CLIENT_NONCE_FIELD_NUMBER: _ClassVar[int]
    DEVICE_NAME_FIELD_NUMBER: _ClassVar[int]
    DISCONNECT_ACTION_FIELD_NUMBER: _ClassVar[int]
    FIRMWARE_VERSION_FIELD_NUMBER: _ClassVar[int]
    HEARTBEAT_TIMEOUT_MS_FIELD_NUMBER: _ClassVar[int]
    HEARTBEAT_TOKEN_FIELD_NUMBER: _ClassVar[int]
    JOINT_COUNT_FIELD_NUMBER: _ClassVar[int]
    LINEAR_UNIT_FIELD_NUMBER: _ClassVar[int]
    OWNER_FIELD_NUMBER: _ClassVar[int]
    PROTOCOL_VERSION_FIELD_NUMBER: _ClassVar[int]
    SCHEMA_HASH_FIELD_NUMBER: _ClassVar[int]
    SESSION_EPOCH_FIELD_NUMBER: _ClassVar[int]
    SESSION_SIGNED_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    angular_unit: AngularUnit
    auth_policy: AuthPolicy
    client_nonce: int
    device_name: str
    disconnect_action: DisconnectAction
    firmware_version: str
    heartbeat_timeout_ms: int
    heartbeat_token: int
    joint_count: int
    linear_unit: LinearUnit
    owner: bool
    protocol_version: int
    schema_hash: int
    session_epoch: int
    session_signed: bool
    state: State
    def __init__(self, protocol_version: _Optional[int] = ..., schema_hash: _Optional[int] = ..., device_name: _Optional[str] = ..., joint_count: _Optional[int] = ..., firmware_version: _Optional[str] = ..., heartbeat_timeout_ms: _Optional[int] = ..., state: _Optional[_Union[State, str]] = ..., owner: bool = ..., session_epoch: _Optional[int] = ..., disconnect_action: _Optional[_Union[DisconnectAction, str]] = ..., linear_unit: _Optional[_Union[LinearUnit, str]] = ..., angular_unit: _Optional[_Union[AngularUnit, str]] = ..., heartbeat_token: _Optional[int] = ..., client_nonce: _Optional[int] = ..., auth_policy: _Optional[_Union[AuthPolicy, str]] = ..., session_signed: bool = ...) -> None: ...

class DeactivateReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class DeactivateRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class DeactivateToolReq(_message.Message):
    __slots__ = ["bit_field", "tool_id"]
    BIT_FIELD_FIELD_NUMBER: _ClassVar[int]
    TOOL_ID_FIELD_NUMBER: _ClassVar[int]
    bit_field: int
    tool_id: str
    def __init__(self, tool_id: _Optional[str] = ..., bit_field: _Optional[int] = ...) -> None: ...

class DeactivateToolRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class DescribeReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class DescribeRes(_message.Message):
    __slots__ = ["auth_policy", "dio_units", "downlink_limits", "field_limits", "frame_angle_max_rad", "homing", "homing_timeout_ms", "joints", "max_angular_accel_rad_s2", "max_angular_speed_rad_s", "max_answer_bytes", "max_cycles", "max_dio_watches", "max_linear_accel_m_s2", "max_linear_speed_m_s", "max_notice_datum_bytes", "max_paths", "max_points_per_path", "max_sessions", "min_rate_pct", "reach_m", "robot_model", "sensors", "tools", "workspace_max_m", "workspace_min_m"]
    AUTH_POLICY_FIELD_NUMBER: _ClassVar[int]
    DIO_UNITS_FIELD_NUMBER: _ClassVar[int]
    DOWNLINK_LIMITS_FIELD_NUMBER: _ClassVar[int]
    FIELD_LIMITS_FIELD_NUMBER: _ClassVar[int]
    FRAME_ANGLE_MAX_RAD_FIELD_NUMBER: _ClassVar[int]
    HOMING_FIELD_NUMBER: _ClassVar[int]
    HOMING_TIMEOUT_MS_FIELD_NUMBER: _ClassVar[int]
    JOINTS_FIELD_NUMBER: _ClassVar[int]
    MAX_ANGULAR_ACCEL_RAD_S2_FIELD_NUMBER: _ClassVar[int]
    MAX_ANGULAR_SPEED_RAD_S_FIELD_NUMBER: _ClassVar[int]
    MAX_ANSWER_BYTES_FIELD_NUMBER: _ClassVar[int]
    MAX_CYCLES_FIELD_NUMBER: _ClassVar[int]
    MAX_DIO_WATCHES_FIELD_NUMBER: _ClassVar[int]
    MAX_LINEAR_ACCEL_M_S2_FIELD_NUMBER: _ClassVar[int]
    MAX_LINEAR_SPEED_M_S_FIELD_NUMBER: _ClassVar[int]
    MAX_NOTICE_DATUM_BYTES_FIELD_NUMBER: _ClassVar[int]
    MAX_PATHS_FIELD_NUMBER: _ClassVar[int]
    MAX_POINTS_PER_PATH_FIELD_NUMBER: _ClassVar[int]
    MAX_SESSIONS_FIELD_NUMBER: _ClassVar[int]
    MIN_RATE_PCT_FIELD_NUMBER: _ClassVar[int]
    REACH_M_FIELD_NUMBER: _ClassVar[int]
    ROBOT_MODEL_FIELD_NUMBER: _ClassVar[int]
    SENSORS_FIELD_NUMBER: _ClassVar[int]
    TOOLS_FIELD_NUMBER: _ClassVar[int]
    WORKSPACE_MAX_M_FIELD_NUMBER: _ClassVar[int]
    WORKSPACE_MIN_M_FIELD_NUMBER: _ClassVar[int]
    auth_policy: AuthPolicy
    dio_units: _containers.RepeatedCompositeFieldContainer[DioUnitInfo]
    downlink_limits: _containers.RepeatedCompositeFieldContainer[FieldLimit]
    field_limits: _containers.RepeatedCompositeFieldContainer[FieldLimit]
    frame_angle_max_rad: float
    homing: _containers.RepeatedCompositeFieldContainer[JointHoming]
    homing_timeout_ms: int
    joints: _containers.RepeatedCompositeFieldContainer[JointLimit]
    max_angular_accel_rad_s2: float
    max_angular_speed_rad_s: float
    max_answer_bytes: int
    max_cycles: int
    max_dio_watches: int
    max_linear_accel_m_s2: float
    max_linear_speed_m_s: float
    max_notice_datum_bytes: int
    max_paths: int
    max_points_per_path: int
    max_sessions: int
    min_rate_pct: float
    reach_m: float
    robot_model: str
    sensors: _containers.RepeatedCompositeFieldContainer[SensorInfo]
    tools: _containers.RepeatedScalarFieldContainer[str]
    workspace_max_m: _containers.RepeatedScalarFieldContainer[float]
    workspace_min_m: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, max_sessions: _Optional[int] = ..., max_paths: _Optional[int] = ..., max_points_per_path: _Optional[int] = ..., max_dio_watches: _Optional[int] = ..., max_cycles: _Optional[int] = ..., min_rate_pct: _Optional[float] = ..., frame_angle_max_rad: _Optional[float] = ..., field_limits: _Optional[_Iterable[_Union[FieldLimit, _Mapping]]] = ..., dio_units: _Optional[_Iterable[_Union[DioUnitInfo, _Mapping]]] = ..., sensors: _Optional[_Iterable[_Union[SensorInfo, _Mapping]]] = ..., tools: _Optional[_Iterable[str]] = ..., robot_model: _Optional[str] = ..., joints: _Optional[_Iterable[_Union[JointLimit, _Mapping]]] = ..., max_linear_speed_m_s: _Optional[float] = ..., max_angular_speed_rad_s: _Optional[float] = ..., max_linear_accel_m_s2: _Optional[float] = ..., max_angular_accel_rad_s2: _Optional[float] = ..., workspace_min_m: _Optional[_Iterable[float]] = ..., workspace_max_m: _Optional[_Iterable[float]] = ..., reach_m: _Optional[float] = ..., max_answer_bytes: _Optional[int] = ..., max_notice_datum_bytes: _Optional[int] = ..., homing: _Optional[_Iterable[_Union[JointHoming, _Mapping]]] = ..., homing_timeout_ms: _Optional[int] = ..., downlink_limits: _Optional[_Iterable[_Union[FieldLimit, _Mapping]]] = ..., auth_policy: _Optional[_Union[AuthPolicy, str]] = ...) -> None: ...

class DescribeRobotReq(_message.Message):
    __slots__ = ["offset"]
    OFFSET_FIELD_NUMBER: _ClassVar[int]
    offset: int
    def __init__(self, offset: _Optional[int] = ...) -> None: ...

class DescribeRobotRes(_message.Message):
    __slots__ = ["ik_class", "offset", "robot_model", "total_bytes", "urdf"]
    IK_CLASS_FIELD_NUMBER: _ClassVar[int]
    OFFSET_FIELD_NUMBER: _ClassVar[int]
    ROBOT_MODEL_FIELD_NUMBER: _ClassVar[int]
    TOTAL_BYTES_FIELD_NUMBER: _ClassVar[int]
    URDF_FIELD_NUMBER: _ClassVar[int]
    ik_class: str
    offset: int
    robot_model: str
    total_bytes: int
    urdf: str
    def __init__(self, urdf: _Optional[str] = ..., offset: _Optional[int] = ..., total_bytes: _Optional[int] = ..., robot_model: _Optional[str] = ..., ik_class: _Optional[str] = ...) -> None: ...

class DioUnitInfo(_message.Message):
    __slots__ = ["input_mask", "output_mask", "unit_id"]
    INPUT_MASK_FIELD_NUMBER: _ClassVar[int]
    OUTPUT_MASK_FIELD_NUMBER: _ClassVar[int]
    UNIT_ID_FIELD_NUMBER: _ClassVar[int]
    input_mask: int
    output_mask: int
    unit_id: int
    def __init__(self, unit_id: _Optional[int] = ..., input_mask: _Optional[int] = ..., output_mask: _Optional[int] = ...) -> None: ...

class DisconnectReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class DisconnectRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class Downlink(_message.Message):
    __slots__ = ["mac", "notice", "response", "rsvp_ack"]
    MAC_FIELD_NUMBER: _ClassVar[int]
    NOTICE_FIELD_NUMBER: _ClassVar[int]
    RESPONSE_FIELD_NUMBER: _ClassVar[int]
    RSVP_ACK_FIELD_NUMBER: _ClassVar[int]
    mac: bytes
    notice: Notice
    response: Response
    rsvp_ack: RsvpAck
    def __init__(self, response: _Optional[_Union[Response, _Mapping]] = ..., notice: _Optional[_Union[Notice, _Mapping]] = ..., rsvp_ack: _Optional[_Union[RsvpAck, _Mapping]] = ..., mac: _Optional[bytes] = ...) -> None: ...

class FieldLimit(_message.Message):
    __slots__ = ["max_bytes", "max_count", "path"]
    MAX_BYTES_FIELD_NUMBER: _ClassVar[int]
    MAX_COUNT_FIELD_NUMBER: _ClassVar[int]
    PATH_FIELD_NUMBER: _ClassVar[int]
    max_bytes: int
    max_count: int
    path: _containers.RepeatedScalarFieldContainer[int]
    def __init__(self, path: _Optional[_Iterable[int]] = ..., max_bytes: _Optional[int] = ..., max_count: _Optional[int] = ...) -> None: ...

class GetAccelerationsReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetAccelerationsRes(_message.Message):
    __slots__ = ["joint_accels", "percent_accel", "world_angular_accel", "world_linear_accel"]
    JOINT_ACCELS_FIELD_NUMBER: _ClassVar[int]
    PERCENT_ACCEL_FIELD_NUMBER: _ClassVar[int]
    WORLD_ANGULAR_ACCEL_FIELD_NUMBER: _ClassVar[int]
    WORLD_LINEAR_ACCEL_FIELD_NUMBER: _ClassVar[int]
    joint_accels: _containers.RepeatedScalarFieldContainer[float]
    percent_accel: float
    world_angular_accel: float
    world_linear_accel: float
    def __init__(self, percent_accel: _Optional[float] = ..., world_linear_accel: _Optional[float] = ..., world_angular_accel: _Optional[float] = ..., joint_accels: _Optional[_Iterable[float]] = ...) -> None: ...

class GetDigitalIOReq(_message.Message):
    __slots__ = ["description", "type", "unit_id"]
    DESCRIPTION_FIELD_NUMBER: _ClassVar[int]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    UNIT_ID_FIELD_NUMBER: _ClassVar[int]
    description: str
    type: str
    unit_id: int
    def __init__(self, type: _Optional[str] = ..., unit_id: _Optional[int] = ..., description: _Optional[str] = ...) -> None: ...

class GetDigitalIORes(_message.Message):
    __slots__ = ["bits_on"]
    BITS_ON_FIELD_NUMBER: _ClassVar[int]
    bits_on: int
    def __init__(self, bits_on: _Optional[int] = ...) -> None: ...

class GetEndEffectorStateReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetEndEffectorStateRes(_message.Message):
    __slots__ = ["current_ee", "ee_state"]
    CURRENT_EE_FIELD_NUMBER: _ClassVar[int]
    EE_STATE_FIELD_NUMBER: _ClassVar[int]
    current_ee: str
    ee_state: str
    def __init__(self, current_ee: _Optional[str] = ..., ee_state: _Optional[str] = ...) -> None: ...

class GetMaxAccelerationsReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetMaxAccelerationsRes(_message.Message):
    __slots__ = ["max_joint_accels", "max_world_angular_accel", "max_world_linear_accel"]
    MAX_JOINT_ACCELS_FIELD_NUMBER: _ClassVar[int]
    MAX_WORLD_ANGULAR_ACCEL_FIELD_NUMBER: _ClassVar[int]
    MAX_WORLD_LINEAR_ACCEL_FIELD_NUMBER: _ClassVar[int]
    max_joint_accels: _containers.RepeatedScalarFieldContainer[float]
    max_world_angular_accel: float
    max_world_linear_accel: float
    def __init__(self, max_world_linear_accel: _Optional[float] = ..., max_world_angular_accel: _Optional[float] = ..., max_joint_accels: _Optional[_Iterable[float]] = ...) -> None: ...

class GetMaxVelocitiesReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetMaxVelocitiesRes(_message.Message):
    __slots__ = ["max_joint_velocities", "max_world_angular_velocity", "max_world_linear_velocity"]
    MAX_JOINT_VELOCITIES_FIELD_NUMBER: _ClassVar[int]
    MAX_WORLD_ANGULAR_VELOCITY_FIELD_NUMBER: _ClassVar[int]
    MAX_WORLD_LINEAR_VELOCITY_FIELD_NUMBER: _ClassVar[int]
    max_joint_velocities: _containers.RepeatedScalarFieldContainer[float]
    max_world_angular_velocity: float
    max_world_linear_velocity: float
    def __init__(self, max_world_linear_velocity: _Optional[float] = ..., max_world_angular_velocity: _Optional[float] = ..., max_joint_velocities: _Optional[_Iterable[float]] = ...) -> None: ...

class GetMotionControlStateReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetMotionControlStateRes(_message.Message):
    __slots__ = ["control_mode", "fault", "motion_control_state", "owner", "state"]
    CONTROL_MODE_FIELD_NUMBER: _ClassVar[int]
    FAULT_FIELD_NUMBER: _ClassVar[int]
    MOTION_CONTROL_STATE_FIELD_NUMBER: _ClassVar[int]
    OWNER_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    control_mode: str
    fault: str
    motion_control_state: str
    owner: bool
    state: State
    def __init__(self, motion_control_state: _Optional[str] = ..., control_mode: _Optional[str] = ..., state: _Optional[_Union[State, str]] = ..., fault: _Optional[str] = ..., owner: bool = ...) -> None: ...

class GetRobotPositionReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetRobotPositionRes(_message.Message):
    __slots__ = ["joints", "world_pose"]
    JOINTS_FIELD_NUMBER: _ClassVar[int]
    WORLD_POSE_FIELD_NUMBER: _ClassVar[int]
    joints: _containers.RepeatedScalarFieldContainer[float]
    world_pose: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, joints: _Optional[_Iterable[float]] = ..., world_pose: _Optional[_Iterable[float]] = ...) -> None: ...

class GetSensorReadingReq(_message.Message):
    __slots__ = ["sensor_type"]
    SENSOR_TYPE_FIELD_NUMBER: _ClassVar[int]
    sensor_type: str
    def __init__(self, sensor_type: _Optional[str] = ...) -> None: ...

class GetSensorReadingRes(_message.Message):
    __slots__ = ["current_data"]
    CURRENT_DATA_FIELD_NUMBER: _ClassVar[int]
    current_data: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, current_data: _Optional[_Iterable[float]] = ...) -> None: ...

class GetTagIdReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetTagIdRes(_message.Message):
    __slots__ = ["path_name", "tag_id"]
    PATH_NAME_FIELD_NUMBER: _ClassVar[int]
    TAG_ID_FIELD_NUMBER: _ClassVar[int]
    path_name: str
    tag_id: str
    def __init__(self, path_name: _Optional[str] = ..., tag_id: _Optional[str] = ...) -> None: ...

class GetToolOffsetsReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetToolOffsetsRes(_message.Message):
    __slots__ = ["offset"]
    OFFSET_FIELD_NUMBER: _ClassVar[int]
    offset: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, offset: _Optional[_Iterable[float]] = ...) -> None: ...

class GetToolReq(_message.Message):
    __slots__ = ["tool_id"]
    TOOL_ID_FIELD_NUMBER: _ClassVar[int]
    tool_id: str
    def __init__(self, tool_id: _Optional[str] = ...) -> None: ...

class GetToolRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetUnitsReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetUnitsRes(_message.Message):
    __slots__ = ["angular_units", "linear_units"]
    ANGULAR_UNITS_FIELD_NUMBER: _ClassVar[int]
    LINEAR_UNITS_FIELD_NUMBER: _ClassVar[int]
    angular_units: str
    linear_units: str
    def __init__(self, linear_units: _Optional[str] = ..., angular_units: _Optional[str] = ...) -> None: ...

class GetVelocitiesReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class GetVelocitiesRes(_message.Message):
    __slots__ = ["joint_velocities", "percent_velocity", "world_angular_velocity", "world_linear_velocity"]
    JOINT_VELOCITIES_FIELD_NUMBER: _ClassVar[int]
    PERCENT_VELOCITY_FIELD_NUMBER: _ClassVar[int]
    WORLD_ANGULAR_VELOCITY_FIELD_NUMBER: _ClassVar[int]
    WORLD_LINEAR_VELOCITY_FIELD_NUMBER: _ClassVar[int]
    joint_velocities: _containers.RepeatedScalarFieldContainer[float]
    percent_velocity: float
    world_angular_velocity: float
    world_linear_velocity: float
    def __init__(self, percent_velocity: _Optional[float] = ..., world_linear_velocity: _Optional[float] = ..., world_angular_velocity: _Optional[float] = ..., joint_velocities: _Optional[_Iterable[float]] = ...) -> None: ...

class JointHoming(_message.Message):
    __slots__ = ["required", "state"]
    REQUIRED_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    required: bool
    state: HomeState
    def __init__(self, required: bool = ..., state: _Optional[_Union[HomeState, str]] = ...) -> None: ...

class JointLimit(_message.Message):
    __slots__ = ["max_accel_rad_s2", "max_rad", "max_velocity_rad_s", "min_rad"]
    MAX_ACCEL_RAD_S2_FIELD_NUMBER: _ClassVar[int]
    MAX_RAD_FIELD_NUMBER: _ClassVar[int]
    MAX_VELOCITY_RAD_S_FIELD_NUMBER: _ClassVar[int]
    MIN_RAD_FIELD_NUMBER: _ClassVar[int]
    max_accel_rad_s2: float
    max_rad: float
    max_velocity_rad_s: float
    min_rad: float
    def __init__(self, min_rad: _Optional[float] = ..., max_rad: _Optional[float] = ..., max_velocity_rad_s: _Optional[float] = ..., max_accel_rad_s2: _Optional[float] = ...) -> None: ...

class LockReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class LockRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ManualControlReq(_message.Message):
    __slots__ = ["type"]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    type: str
    def __init__(self, type: _Optional[str] = ...) -> None: ...

class ManualControlRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class MoveAbsoluteReq(_message.Message):
    __slots__ = ["frame", "point_name", "speed_pct", "values"]
    FRAME_FIELD_NUMBER: _ClassVar[int]
    POINT_NAME_FIELD_NUMBER: _ClassVar[int]
    SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    VALUES_FIELD_NUMBER: _ClassVar[int]
    frame: ReferenceFrame
    point_name: str
    speed_pct: float
    values: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, point_name: _Optional[str] = ..., frame: _Optional[_Union[ReferenceFrame, str]] = ..., values: _Optional[_Iterable[float]] = ..., speed_pct: _Optional[float] = ...) -> None: ...

class MoveAbsoluteRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class MoveArcReq(_message.Message):
    __slots__ = ["arc_value", "frame", "goal_value", "offset_type", "point_name"]
    ARC_VALUE_FIELD_NUMBER: _ClassVar[int]
    FRAME_FIELD_NUMBER: _ClassVar[int]
    GOAL_VALUE_FIELD_NUMBER: _ClassVar[int]
    OFFSET_TYPE_FIELD_NUMBER: _ClassVar[int]
    POINT_NAME_FIELD_NUMBER: _ClassVar[int]
    arc_value: _containers.RepeatedScalarFieldContainer[float]
    frame: ReferenceFrame
    goal_value: _containers.RepeatedScalarFieldContainer[float]
    offset_type: OffsetType
    point_name: str
    def __init__(self, point_name: _Optional[str] = ..., frame: _Optional[_Union[ReferenceFrame, str]] = ..., offset_type: _Optional[_Union[OffsetType, str]] = ..., arc_value: _Optional[_Iterable[float]] = ..., goal_value: _Optional[_Iterable[float]] = ...) -> None: ...

class MoveArcRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class MoveReactReq(_message.Message):
    __slots__ = ["compliance_speed_pct", "envelope_max", "envelope_min", "gains", "motion_offsets", "motion_speed_pct", "sensor_type", "thresholds"]
    COMPLIANCE_SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    ENVELOPE_MAX_FIELD_NUMBER: _ClassVar[int]
    ENVELOPE_MIN_FIELD_NUMBER: _ClassVar[int]
    GAINS_FIELD_NUMBER: _ClassVar[int]
    MOTION_OFFSETS_FIELD_NUMBER: _ClassVar[int]
    MOTION_SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    SENSOR_TYPE_FIELD_NUMBER: _ClassVar[int]
    THRESHOLDS_FIELD_NUMBER: _ClassVar[int]
    compliance_speed_pct: float
    envelope_max: _containers.RepeatedScalarFieldContainer[float]
    envelope_min: _containers.RepeatedScalarFieldContainer[float]
    gains: _containers.RepeatedScalarFieldContainer[float]
    motion_offsets: _containers.RepeatedScalarFieldContainer[float]
    motion_speed_pct: float
    sensor_type: str
    thresholds: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, sensor_type: _Optional[str] = ..., motion_offsets: _Optional[_Iterable[float]] = ..., motion_speed_pct: _Optional[float] = ..., compliance_speed_pct: _Optional[float] = ..., thresholds: _Optional[_Iterable[float]] = ..., gains: _Optional[_Iterable[float]] = ..., envelope_min: _Optional[_Iterable[float]] = ..., envelope_max: _Optional[_Iterable[float]] = ...) -> None: ...

class MoveReactRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class MoveRelativeReq(_message.Message):
    __slots__ = ["frame", "point_name", "speed_pct", "values"]
    FRAME_FIELD_NUMBER: _ClassVar[int]
    POINT_NAME_FIELD_NUMBER: _ClassVar[int]
    SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    VALUES_FIELD_NUMBER: _ClassVar[int]
    frame: ReferenceFrame
    point_name: str
    speed_pct: float
    values: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, point_name: _Optional[str] = ..., frame: _Optional[_Union[ReferenceFrame, str]] = ..., values: _Optional[_Iterable[float]] = ..., speed_pct: _Optional[float] = ...) -> None: ...

class MoveRelativeRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class Notice(_message.Message):
    __slots__ = ["data", "event_id", "final", "kind", "notice_seq", "ref_seq", "rsvp_default", "rsvp_id", "rsvp_timeout_ms", "session_epoch"]
    DATA_FIELD_NUMBER: _ClassVar[int]
    EVENT_ID_FIELD_NUMBER: _ClassVar[int]
    FINAL_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    NOTICE_SEQ_FIELD_NUMBER: _ClassVar[int]
    REF_SEQ_FIELD_NUMBER: _ClassVar[int]
    RSVP_DEFAULT_FIELD_NUMBER: _ClassVar[int]
    RSVP_ID_FIELD_NUMBER: _ClassVar[int]
    RSVP_TIMEOUT_MS_FIELD_NUMBER: _ClassVar[int]
    SESSION_EPOCH_FIELD_NUMBER: _ClassVar[int]
    data: _containers.RepeatedScalarFieldContainer[str]
    event_id: str
    final: bool
    kind: NoticeKind
    notice_seq: int
    ref_seq: int
    rsvp_default: str
    rsvp_id: int
    rsvp_timeout_ms: int
    session_epoch: int
    def __init__(self, kind: _Optional[_Union[NoticeKind, str]] = ..., event_id: _Optional[str] = ..., data: _Optional[_Iterable[str]] = ..., ref_seq: _Optional[int] = ..., rsvp_id: _Optional[int] = ..., rsvp_timeout_ms: _Optional[int] = ..., rsvp_default: _Optional[str] = ..., notice_seq: _Optional[int] = ..., final: bool = ..., session_epoch: _Optional[int] = ...) -> None: ...

class PathClearPathReq(_message.Message):
    __slots__ = ["path_name"]
    PATH_NAME_FIELD_NUMBER: _ClassVar[int]
    path_name: str
    def __init__(self, path_name: _Optional[str] = ...) -> None: ...

class PathClearPathRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class PathLoadReq(_message.Message):
    __slots__ = ["frame", "motion_type", "number_of_points", "offset_type", "path_name", "tags"]
    FRAME_FIELD_NUMBER: _ClassVar[int]
    MOTION_TYPE_FIELD_NUMBER: _ClassVar[int]
    NUMBER_OF_POINTS_FIELD_NUMBER: _ClassVar[int]
    OFFSET_TYPE_FIELD_NUMBER: _ClassVar[int]
    PATH_NAME_FIELD_NUMBER: _ClassVar[int]
    TAGS_FIELD_NUMBER: _ClassVar[int]
    frame: ReferenceFrame
    motion_type: MotionType
    number_of_points: int
    offset_type: OffsetType
    path_name: str
    tags: _containers.RepeatedCompositeFieldContainer[TagPoint]
    def __init__(self, path_name: _Optional[str] = ..., frame: _Optional[_Union[ReferenceFrame, str]] = ..., motion_type: _Optional[_Union[MotionType, str]] = ..., offset_type: _Optional[_Union[OffsetType, str]] = ..., number_of_points: _Optional[int] = ..., tags: _Optional[_Iterable[_Union[TagPoint, _Mapping]]] = ...) -> None: ...

class PathLoadRes(_message.Message):
    __slots__ = ["points_in_path"]
    POINTS_IN_PATH_FIELD_NUMBER: _ClassVar[int]
    points_in_path: int
    def __init__(self, points_in_path: _Optional[int] = ...) -> None: ...

class PathMoveReq(_message.Message):
    __slots__ = ["number_of_cycles", "path_name"]
    NUMBER_OF_CYCLES_FIELD_NUMBER: _ClassVar[int]
    PATH_NAME_FIELD_NUMBER: _ClassVar[int]
    number_of_cycles: int
    path_name: str
    def __init__(self, path_name: _Optional[str] = ..., number_of_cycles: _Optional[int] = ...) -> None: ...

class PathMoveRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class PutToolReq(_message.Message):
    __slots__ = ["tool_id"]
    TOOL_ID_FIELD_NUMBER: _ClassVar[int]
    tool_id: str
    def __init__(self, tool_id: _Optional[str] = ...) -> None: ...

class PutToolRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ReleaseReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ReleaseRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class Request(_message.Message):
    __slots__ = ["abort_motion", "activate", "activate_tool", "challenge", "comply", "connect", "deactivate", "deactivate_tool", "describe", "describe_robot", "disconnect", "get_accelerations", "get_digital_io", "get_end_effector_state", "get_max_accelerations", "get_max_velocities", "get_motion_control_state", "get_robot_position", "get_sensor_reading", "get_tag_id", "get_tool", "get_tool_offsets", "get_units", "get_velocities", "lock", "manual_control", "move_absolute", "move_arc", "move_react", "move_relative", "path_clear_path", "path_load", "path_move", "put_tool", "release", "resume_motion", "send_command", "seq", "set_acceleration", "set_digital_io", "set_speed", "set_tool_offset", "set_units", "set_world_cartesian_frame", "signal_digital_io", "stop_motion"]
    ABORT_MOTION_FIELD_NUMBER: _ClassVar[int]
    ACTIVATE_FIELD_NUMBER: _ClassVar[int]
    ACTIVATE_TOOL_FIELD_NUMBER: _ClassVar[int]
    CHALLENGE_FIELD_NUMBER: _ClassVar[int]
    COMPLY_FIELD_NUMBER: _ClassVar[int]
    CONNECT_FIELD_NUMBER: _ClassVar[int]
    DEACTIVATE_FIELD_NUMBER: _ClassVar[int]
    DEACTIVATE_TOOL_FIELD_NUMBER: _ClassVar[int]
    DESCRIBE_FIELD_NUMBER: _ClassVar[int]
    DESCRIBE_ROBOT_FIELD_NUMBER: _ClassVar[int]
    DISCONNECT_FIELD_NUMBER: _ClassVar[int]
    GET_ACCELERATIONS_FIELD_NUMBER: _ClassVar[int]
    GET_DIGITAL_IO_FIELD_NUMBER: _ClassVar[int]
    GET_END_EFFECTOR_STATE_FIELD_NUMBER: _ClassVar[int]
    GET_MAX_ACCELERATIONS_FIELD_NUMBER: _ClassVar[int]
    GET_MAX_VELOCITIES_FIELD_NUMBER: _ClassVar[int]
    GET_MOTION_CONTROL_STATE_FIELD_NUMBER: _ClassVar[int]
    GET_ROBOT_POSITION_FIELD_NUMBER: _ClassVar[int]
    GET_SENSOR_READING_FIELD_NUMBER: _ClassVar[int]
    GET_TAG_ID_FIELD_NUMBER: _ClassVar[int]
    GET_TOOL_FIELD_NUMBER: _ClassVar[int]
    GET_TOOL_OFFSETS_FIELD_NUMBER: _ClassVar[int]
    GET_UNITS_FIELD_NUMBER: _ClassVar[int]
    GET_VELOCITIES_FIELD_NUMBER: _ClassVar[int]
    LOCK_FIELD_NUMBER: _ClassVar[int]
    MANUAL_CONTROL_FIELD_NUMBER: _ClassVar[int]
    MOVE_ABSOLUTE_FIELD_NUMBER: _ClassVar[int]
    MOVE_ARC_FIELD_NUMBER: _ClassVar[int]
    MOVE_REACT_FIELD_NUMBER: _ClassVar[int]
    MOVE_RELATIVE_FIELD_NUMBER: _ClassVar[int]
    PATH_CLEAR_PATH_FIELD_NUMBER: _ClassVar[int]
    PATH_LOAD_FIELD_NUMBER: _ClassVar[int]
    PATH_MOVE_FIELD_NUMBER: _ClassVar[int]
    PUT_TOOL_FIELD_NUMBER: _ClassVar[int]
    RELEASE_FIELD_NUMBER: _ClassVar[int]
    RESUME_MOTION_FIELD_NUMBER: _ClassVar[int]
    SEND_COMMAND_FIELD_NUMBER: _ClassVar[int]
    SEQ_FIELD_NUMBER: _ClassVar[int]
    SET_ACCELERATION_FIELD_NUMBER: _ClassVar[int]
    SET_DIGITAL_IO_FIELD_NUMBER: _ClassVar[int]
    SET_SPEED_FIELD_NUMBER: _ClassVar[int]
    SET_TOOL_OFFSET_FIELD_NUMBER: _ClassVar[int]
    SET_UNITS_FIELD_NUMBER: _ClassVar[int]
    SET_WORLD_CARTESIAN_FRAME_FIELD_NUMBER: _ClassVar[int]
    SIGNAL_DIGITAL_IO_FIELD_NUMBER: _ClassVar[int]
    STOP_MOTION_FIELD_NUMBER: _ClassVar[int]
    abort_motion: AbortMotionReq
    activate: ActivateReq
    activate_tool: ActivateToolReq
    challenge: ChallengeReq
    comply: ComplyReq
    connect: ConnectReq
    deactivate: DeactivateReq
    deactivate_tool: DeactivateToolReq
    describe: DescribeReq
    describe_robot: DescribeRobotReq
    disconnect: DisconnectReq
    get_accelerations: GetAccelerationsReq
    get_digital_io: GetDigitalIOReq
    get_end_effector_state: GetEndEffectorStateReq
    get_max_accelerations: GetMaxAccelerationsReq
    get_max_velocities: GetMaxVelocitiesReq
    get_motion_control_state: GetMotionControlStateReq
    get_robot_position: GetRobotPositionReq
    get_sensor_reading: GetSensorReadingReq
    get_tag_id: GetTagIdReq
    get_tool: GetToolReq
    get_tool_offsets: GetToolOffsetsReq
    get_units: GetUnitsReq
    get_velocities: GetVelocitiesReq
    lock: LockReq
    manual_control: ManualControlReq
    move_absolute: MoveAbsoluteReq
    move_arc: MoveArcReq
    move_react: MoveReactReq
    move_relative: MoveRelativeReq
    path_clear_path: PathClearPathReq
    path_load: PathLoadReq
    path_move: PathMoveReq
    put_tool: PutToolReq
    release: ReleaseReq
    resume_motion: ResumeMotionReq
    send_command: SendCommandReq
    seq: int
    set_acceleration: SetAccelerationReq
    set_digital_io: SetDigitalIOReq
    set_speed: SetSpeedReq
    set_tool_offset: SetToolOffsetReq
    set_units: SetUnitsReq
    set_world_cartesian_frame: SetWorldCartesianFrameReq
    signal_digital_io: SignalDigitalIOReq
    stop_motion: StopMotionReq
    def __init__(self, seq: _Optional[int] = ..., connect: _Optional[_Union[ConnectReq, _Mapping]] = ..., disconnect: _Optional[_Union[DisconnectReq, _Mapping]] = ..., lock: _Optional[_Union[LockReq, _Mapping]] = ..., release: _Optional[_Union[ReleaseReq, _Mapping]] = ..., activate: _Optional[_Union[ActivateReq, _Mapping]] = ..., deactivate: _Optional[_Union[DeactivateReq, _Mapping]] = ..., set_speed: _Optional[_Union[SetSpeedReq, _Mapping]] = ..., set_acceleration: _Optional[_Union[SetAccelerationReq, _Mapping]] = ..., set_tool_offset: _Optional[_Union[SetToolOffsetReq, _Mapping]] = ..., set_world_cartesian_frame: _Optional[_Union[SetWorldCartesianFrameReq, _Mapping]] = ..., set_units: _Optional[_Union[SetUnitsReq, _Mapping]] = ..., get_units: _Optional[_Union[GetUnitsReq, _Mapping]] = ..., get_velocities: _Optional[_Union[GetVelocitiesReq, _Mapping]] = ..., get_accelerations: _Optional[_Union[GetAccelerationsReq, _Mapping]] = ..., get_max_velocities: _Optional[_Union[GetMaxVelocitiesReq, _Mapping]] = ..., get_max_accelerations: _Optional[_Union[GetMaxAccelerationsReq, _Mapping]] = ..., get_tool_offsets: _Optional[_Union[GetToolOffsetsReq, _Mapping]] = ..., get_robot_position: _Optional[_Union[GetRobotPositionReq, _Mapping]] = ..., get_motion_control_state: _Optional[_Union[GetMotionControlStateReq, _Mapping]] = ..., get_tag_id: _Optional[_Union[GetTagIdReq, _Mapping]] = ..., move_relative: _Optional[_Union[MoveRelativeReq, _Mapping]] = ..., move_absolute: _Optional[_Union[MoveAbsoluteReq, _Mapping]] = ..., move_arc: _Optional[_Union[MoveArcReq, _Mapping]] = ..., path_load: _Optional[_Union[PathLoadReq, _Mapping]] = ..., path_clear_path: _Optional[_Union[PathClearPathReq, _Mapping]] = ..., path_move: _Optional[_Union[PathMoveReq, _Mapping]] = ..., stop_motion: _Optional[_Union[StopMotionReq, _Mapping]] = ..., resume_motion: _Optional[_Union[ResumeMotionReq, _Mapping]] = ..., abort_motion: _Optional[_Union[AbortMotionReq, _Mapping]] = ..., get_sensor_reading: _Optional[_Union[GetSensorReadingReq, _Mapping]] = ..., move_react: _Optional[_Union[MoveReactReq, _Mapping]] = ..., comply: _Optional[_Union[ComplyReq, _Mapping]] = ..., manual_control: _Optional[_Union[ManualControlReq, _Mapping]] = ..., get_end_effector_state: _Optional[_Union[GetEndEffectorStateReq, _Mapping]] = ..., get_tool: _Optional[_Union[GetToolReq, _Mapping]] = ..., put_tool: _Optional[_Union[PutToolReq, _Mapping]] = ..., activate_tool: _Optional[_Union[ActivateToolReq, _Mapping]] = ..., deactivate_tool: _Optional[_Union[DeactivateToolReq, _Mapping]] = ..., set_digital_io: _Optional[_Union[SetDigitalIOReq, _Mapping]] = ..., get_digital_io: _Optional[_Union[GetDigitalIOReq, _Mapping]] = ..., signal_digital_io: _Optional[_Union[SignalDigitalIOReq, _Mapping]] = ..., send_command: _Optional[_Union[SendCommandReq, _Mapping]] = ..., describe: _Optional[_Union[DescribeReq, _Mapping]] = ..., describe_robot: _Optional[_Union[DescribeRobotReq, _Mapping]] = ..., challenge: _Optional[_Union[ChallengeReq, _Mapping]] = ...) -> None: ...

class Response(_message.Message):
    __slots__ = ["abort_motion", "activate", "activate_tool", "challenge", "comply", "connect", "deactivate", "deactivate_tool", "describe", "describe_robot", "disconnect", "get_accelerations", "get_digital_io", "get_end_effector_state", "get_max_accelerations", "get_max_velocities", "get_motion_control_state", "get_robot_position", "get_sensor_reading", "get_tag_id", "get_tool", "get_tool_offsets", "get_units", "get_velocities", "lock", "manual_control", "move_absolute", "move_arc", "move_react", "move_relative", "path_clear_path", "path_load", "path_move", "put_tool", "release", "resume_motion", "ret_code", "ret_msg", "send_command", "seq", "session_epoch", "set_acceleration", "set_digital_io", "set_speed", "set_tool_offset", "set_units", "set_world_cartesian_frame", "signal_digital_io", "stop_motion"]
    ABORT_MOTION_FIELD_NUMBER: _ClassVar[int]
    ACTIVATE_FIELD_NUMBER: _ClassVar[int]
    ACTIVATE_TOOL_FIELD_NUMBER: _ClassVar[int]
    CHALLENGE_FIELD_NUMBER: _ClassVar[int]
    COMPLY_FIELD_NUMBER: _ClassVar[int]
    CONNECT_FIELD_NUMBER: _ClassVar[int]
    DEACTIVATE_FIELD_NUMBER: _ClassVar[int]
    DEACTIVATE_TOOL_FIELD_NUMBER: _ClassVar[int]
    DESCRIBE_FIELD_NUMBER: _ClassVar[int]
    DESCRIBE_ROBOT_FIELD_NUMBER: _ClassVar[int]
    DISCONNECT_FIELD_NUMBER: _ClassVar[int]
    GET_ACCELERATIONS_FIELD_NUMBER: _ClassVar[int]
    GET_DIGITAL_IO_FIELD_NUMBER: _ClassVar[int]
    GET_END_EFFECTOR_STATE_FIELD_NUMBER: _ClassVar[int]
    GET_MAX_ACCELERATIONS_FIELD_NUMBER: _ClassVar[int]
    GET_MAX_VELOCITIES_FIELD_NUMBER: _ClassVar[int]
    GET_MOTION_CONTROL_STATE_FIELD_NUMBER: _ClassVar[int]
    GET_ROBOT_POSITION_FIELD_NUMBER: _ClassVar[int]
    GET_SENSOR_READING_FIELD_NUMBER: _ClassVar[int]
    GET_TAG_ID_FIELD_NUMBER: _ClassVar[int]
    GET_TOOL_FIELD_NUMBER: _ClassVar[int]
    GET_TOOL_OFFSETS_FIELD_NUMBER: _ClassVar[int]
    GET_UNITS_FIELD_NUMBER: _ClassVar[int]
    GET_VELOCITIES_FIELD_NUMBER: _ClassVar[int]
    LOCK_FIELD_NUMBER: _ClassVar[int]
    MANUAL_CONTROL_FIELD_NUMBER: _ClassVar[int]
    MOVE_ABSOLUTE_FIELD_NUMBER: _ClassVar[int]
    MOVE_ARC_FIELD_NUMBER: _ClassVar[int]
    MOVE_REACT_FIELD_NUMBER: _ClassVar[int]
    MOVE_RELATIVE_FIELD_NUMBER: _ClassVar[int]
    PATH_CLEAR_PATH_FIELD_NUMBER: _ClassVar[int]
    PATH_LOAD_FIELD_NUMBER: _ClassVar[int]
    PATH_MOVE_FIELD_NUMBER: _ClassVar[int]
    PUT_TOOL_FIELD_NUMBER: _ClassVar[int]
    RELEASE_FIELD_NUMBER: _ClassVar[int]
    RESUME_MOTION_FIELD_NUMBER: _ClassVar[int]
    RET_CODE_FIELD_NUMBER: _ClassVar[int]
    RET_MSG_FIELD_NUMBER: _ClassVar[int]
    SEND_COMMAND_FIELD_NUMBER: _ClassVar[int]
    SEQ_FIELD_NUMBER: _ClassVar[int]
    SESSION_EPOCH_FIELD_NUMBER: _ClassVar[int]
    SET_ACCELERATION_FIELD_NUMBER: _ClassVar[int]
    SET_DIGITAL_IO_FIELD_NUMBER: _ClassVar[int]
    SET_SPEED_FIELD_NUMBER: _ClassVar[int]
    SET_TOOL_OFFSET_FIELD_NUMBER: _ClassVar[int]
    SET_UNITS_FIELD_NUMBER: _ClassVar[int]
    SET_WORLD_CARTESIAN_FRAME_FIELD_NUMBER: _ClassVar[int]
    SIGNAL_DIGITAL_IO_FIELD_NUMBER: _ClassVar[int]
    STOP_MOTION_FIELD_NUMBER: _ClassVar[int]
    abort_motion: AbortMotionRes
    activate: ActivateRes
    activate_tool: ActivateToolRes
    challenge: ChallengeRes
    comply: ComplyRes
    connect: ConnectRes
    deactivate: DeactivateRes
    deactivate_tool: DeactivateToolRes
    describe: DescribeRes
    describe_robot: DescribeRobotRes
    disconnect: DisconnectRes
    get_accelerations: GetAccelerationsRes
    get_digital_io: GetDigitalIORes
    get_end_effector_state: GetEndEffectorStateRes
    get_max_accelerations: GetMaxAccelerationsRes
    get_max_velocities: GetMaxVelocitiesRes
    get_motion_control_state: GetMotionControlStateRes
    get_robot_position: GetRobotPositionRes
    get_sensor_reading: GetSensorReadingRes
    get_tag_id: GetTagIdRes
    get_tool: GetToolRes
    get_tool_offsets: GetToolOffsetsRes
    get_units: GetUnitsRes
    get_velocities: GetVelocitiesRes
    lock: LockRes
    manual_control: ManualControlRes
    move_absolute: MoveAbsoluteRes
    move_arc: MoveArcRes
    move_react: MoveReactRes
    move_relative: MoveRelativeRes
    path_clear_path: PathClearPathRes
    path_load: PathLoadRes
    path_move: PathMoveRes
    put_tool: PutToolRes
    release: ReleaseRes
    resume_motion: ResumeMotionRes
    ret_code: int
    ret_msg: str
    send_command: SendCommandRes
    seq: int
    session_epoch: int
    set_acceleration: SetAccelerationRes
    set_digital_io: SetDigitalIORes
    set_speed: SetSpeedRes
    set_tool_offset: SetToolOffsetRes
    set_units: SetUnitsRes
    set_world_cartesian_frame: SetWorldCartesianFrameRes
    signal_digital_io: SignalDigitalIORes
    stop_motion: StopMotionRes
    def __init__(self, seq: _Optional[int] = ..., ret_code: _Optional[int] = ..., ret_msg: _Optional[str] = ..., session_epoch: _Optional[int] = ..., connect: _Optional[_Union[ConnectRes, _Mapping]] = ..., disconnect: _Optional[_Union[DisconnectRes, _Mapping]] = ..., lock: _Optional[_Union[LockRes, _Mapping]] = ..., release: _Optional[_Union[ReleaseRes, _Mapping]] = ..., activate: _Optional[_Union[ActivateRes, _Mapping]] = ..., deactivate: _Optional[_Union[DeactivateRes, _Mapping]] = ..., set_speed: _Optional[_Union[SetSpeedRes, _Mapping]] = ..., set_acceleration: _Optional[_Union[SetAccelerationRes, _Mapping]] = ..., set_tool_offset: _Optional[_Union[SetToolOffsetRes, _Mapping]] = ..., set_world_cartesian_frame: _Optional[_Union[SetWorldCartesianFrameRes, _Mapping]] = ..., set_units: _Optional[_Union[SetUnitsRes, _Mapping]] = ..., get_units: _Optional[_Union[GetUnitsRes, _Mapping]] = ..., get_velocities: _Optional[_Union[GetVelocitiesRes, _Mapping]] = ..., get_accelerations: _Optional[_Union[GetAccelerationsRes, _Mapping]] = ..., get_max_velocities: _Optional[_Union[GetMaxVelocitiesRes, _Mapping]] = ..., get_max_accelerations: _Optional[_Union[GetMaxAccelerationsRes, _Mapping]] = ..., get_tool_offsets: _Optional[_Union[GetToolOffsetsRes, _Mapping]] = ..., get_robot_position: _Optional[_Union[GetRobotPositionRes, _Mapping]] = ..., get_motion_control_state: _Optional[_Union[GetMotionControlStateRes, _Mapping]] = ..., get_tag_id: _Optional[_Union[GetTagIdRes, _Mapping]] = ..., move_relative: _Optional[_Union[MoveRelativeRes, _Mapping]] = ..., move_absolute: _Optional[_Union[MoveAbsoluteRes, _Mapping]] = ..., move_arc: _Optional[_Union[MoveArcRes, _Mapping]] = ..., path_load: _Optional[_Union[PathLoadRes, _Mapping]] = ..., path_clear_path: _Optional[_Union[PathClearPathRes, _Mapping]] = ..., path_move: _Optional[_Union[PathMoveRes, _Mapping]] = ..., stop_motion: _Optional[_Union[StopMotionRes, _Mapping]] = ..., resume_motion: _Optional[_Union[ResumeMotionRes, _Mapping]] = ..., abort_motion: _Optional[_Union[AbortMotionRes, _Mapping]] = ..., get_sensor_reading: _Optional[_Union[GetSensorReadingRes, _Mapping]] = ..., move_react: _Optional[_Union[MoveReactRes, _Mapping]] = ..., comply: _Optional[_Union[ComplyRes, _Mapping]] = ..., manual_control: _Optional[_Union[ManualControlRes, _Mapping]] = ..., get_end_effector_state: _Optional[_Union[GetEndEffectorStateRes, _Mapping]] = ..., get_tool: _Optional[_Union[GetToolRes, _Mapping]] = ..., put_tool: _Optional[_Union[PutToolRes, _Mapping]] = ..., activate_tool: _Optional[_Union[ActivateToolRes, _Mapping]] = ..., deactivate_tool: _Optional[_Union[DeactivateToolRes, _Mapping]] = ..., set_digital_io: _Optional[_Union[SetDigitalIORes, _Mapping]] = ..., get_digital_io: _Optional[_Union[GetDigitalIORes, _Mapping]] = ..., signal_digital_io: _Optional[_Union[SignalDigitalIORes, _Mapping]] = ..., send_command: _Optional[_Union[SendCommandRes, _Mapping]] = ..., describe: _Optional[_Union[DescribeRes, _Mapping]] = ..., describe_robot: _Optional[_Union[DescribeRobotRes, _Mapping]] = ..., challenge: _Optional[_Union[ChallengeRes, _Mapping]] = ...) -> None: ...

class ResumeMotionReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class ResumeMotionRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class RsvpAck(_message.Message):
    __slots__ = ["action", "notice_seq", "ref_seq", "ret_code", "ret_msg", "rsvp_id", "session_epoch"]
    ACTION_FIELD_NUMBER: _ClassVar[int]
    NOTICE_SEQ_FIELD_NUMBER: _ClassVar[int]
    REF_SEQ_FIELD_NUMBER: _ClassVar[int]
    RET_CODE_FIELD_NUMBER: _ClassVar[int]
    RET_MSG_FIELD_NUMBER: _ClassVar[int]
    RSVP_ID_FIELD_NUMBER: _ClassVar[int]
    SESSION_EPOCH_FIELD_NUMBER: _ClassVar[int]
    action: str
    notice_seq: int
    ref_seq: int
    ret_code: int
    ret_msg: str
    rsvp_id: int
    session_epoch: int
    def __init__(self, rsvp_id: _Optional[int] = ..., ret_code: _Optional[int] = ..., ret_msg: _Optional[str] = ..., action: _Optional[str] = ..., ref_seq: _Optional[int] = ..., session_epoch: _Optional[int] = ..., notice_seq: _Optional[int] = ...) -> None: ...

class RsvpReply(_message.Message):
    __slots__ = ["data", "ret_code", "rsvp_id"]
    DATA_FIELD_NUMBER: _ClassVar[int]
    RET_CODE_FIELD_NUMBER: _ClassVar[int]
    RSVP_ID_FIELD_NUMBER: _ClassVar[int]
    data: _containers.RepeatedScalarFieldContainer[str]
    ret_code: int
    rsvp_id: int
    def __init__(self, rsvp_id: _Optional[int] = ..., ret_code: _Optional[int] = ..., data: _Optional[_Iterable[str]] = ...) -> None: ...

class SendCommandReq(_message.Message):
    __slots__ = ["input"]
    INPUT_FIELD_NUMBER: _ClassVar[int]
    input: str
    def __init__(self, input: _Optional[str] = ...) -> None: ...

class SendCommandRes(_message.Message):
    __slots__ = ["result"]
    RESULT_FIELD_NUMBER: _ClassVar[int]
    result: str
    def __init__(self, result: _Optional[str] = ...) -> None: ...

class SensorComponent(_message.Message):
    __slots__ = ["name", "unit"]
    NAME_FIELD_NUMBER: _ClassVar[int]
    UNIT_FIELD_NUMBER: _ClassVar[int]
    name: str
    unit: str
    def __init__(self, name: _Optional[str] = ..., unit: _Optional[str] = ...) -> None: ...

class SensorInfo(_message.Message):
    __slots__ = ["components", "name"]
    COMPONENTS_FIELD_NUMBER: _ClassVar[int]
    NAME_FIELD_NUMBER: _ClassVar[int]
    components: _containers.RepeatedCompositeFieldContainer[SensorComponent]
    name: str
    def __init__(self, name: _Optional[str] = ..., components: _Optional[_Iterable[_Union[SensorComponent, _Mapping]]] = ...) -> None: ...

class SetAccelerationReq(_message.Message):
    __slots__ = ["accel", "attribute"]
    ACCEL_FIELD_NUMBER: _ClassVar[int]
    ATTRIBUTE_FIELD_NUMBER: _ClassVar[int]
    accel: float
    attribute: AccelType
    def __init__(self, accel: _Optional[float] = ..., attribute: _Optional[_Union[AccelType, str]] = ...) -> None: ...

class SetAccelerationRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class SetDigitalIOReq(_message.Message):
    __slots__ = ["bits_off", "bits_on", "description", "type", "unit_id"]
    BITS_OFF_FIELD_NUMBER: _ClassVar[int]
    BITS_ON_FIELD_NUMBER: _ClassVar[int]
    DESCRIPTION_FIELD_NUMBER: _ClassVar[int]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    UNIT_ID_FIELD_NUMBER: _ClassVar[int]
    bits_off: int
    bits_on: int
    description: str
    type: str
    unit_id: int
    def __init__(self, type: _Optional[str] = ..., unit_id: _Optional[int] = ..., bits_on: _Optional[int] = ..., bits_off: _Optional[int] = ..., description: _Optional[str] = ...) -> None: ...

class SetDigitalIORes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class SetSpeedReq(_message.Message):
    __slots__ = ["attribute", "speed"]
    ATTRIBUTE_FIELD_NUMBER: _ClassVar[int]
    SPEED_FIELD_NUMBER: _ClassVar[int]
    attribute: SpeedType
    speed: float
    def __init__(self, speed: _Optional[float] = ..., attribute: _Optional[_Union[SpeedType, str]] = ...) -> None: ...

class SetSpeedRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class SetToolOffsetReq(_message.Message):
    __slots__ = ["offset"]
    OFFSET_FIELD_NUMBER: _ClassVar[int]
    offset: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, offset: _Optional[_Iterable[float]] = ...) -> None: ...

class SetToolOffsetRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class SetUnitsReq(_message.Message):
    __slots__ = ["angular", "linear"]
    ANGULAR_FIELD_NUMBER: _ClassVar[int]
    LINEAR_FIELD_NUMBER: _ClassVar[int]
    angular: AngularUnit
    linear: LinearUnit
    def __init__(self, linear: _Optional[_Union[LinearUnit, str]] = ..., angular: _Optional[_Union[AngularUnit, str]] = ...) -> None: ...

class SetUnitsRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class SetWorldCartesianFrameReq(_message.Message):
    __slots__ = ["frame"]
    FRAME_FIELD_NUMBER: _ClassVar[int]
    frame: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, frame: _Optional[_Iterable[float]] = ...) -> None: ...

class SetWorldCartesianFrameRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class SignalDigitalIOReq(_message.Message):
    __slots__ = ["bit_string", "callback_type", "polling_cycle_time_ms", "polling_timeout_ms", "type", "unit_id"]
    BIT_STRING_FIELD_NUMBER: _ClassVar[int]
    CALLBACK_TYPE_FIELD_NUMBER: _ClassVar[int]
    POLLING_CYCLE_TIME_MS_FIELD_NUMBER: _ClassVar[int]
    POLLING_TIMEOUT_MS_FIELD_NUMBER: _ClassVar[int]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    UNIT_ID_FIELD_NUMBER: _ClassVar[int]
    bit_string: int
    callback_type: CallbackType
    polling_cycle_time_ms: int
    polling_timeout_ms: int
    type: str
    unit_id: int
    def __init__(self, type: _Optional[str] = ..., unit_id: _Optional[int] = ..., bit_string: _Optional[int] = ..., polling_timeout_ms: _Optional[int] = ..., polling_cycle_time_ms: _Optional[int] = ..., callback_type: _Optional[_Union[CallbackType, str]] = ...) -> None: ...

class SignalDigitalIORes(_message.Message):
    __slots__ = ["watch_id"]
    WATCH_ID_FIELD_NUMBER: _ClassVar[int]
    watch_id: int
    def __init__(self, watch_id: _Optional[int] = ...) -> None: ...

class StopMotionReq(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class StopMotionRes(_message.Message):
    __slots__ = []
    def __init__(self) -> None: ...

class TagPoint(_message.Message):
    __slots__ = ["accel_pct", "aux_commands", "joints", "pose", "speed_pct", "tag_index", "tag_name", "time_delay_s", "transition_speed_pct"]
    ACCEL_PCT_FIELD_NUMBER: _ClassVar[int]
    AUX_COMMANDS_FIELD_NUMBER: _ClassVar[int]
    JOINTS_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    TAG_INDEX_FIELD_NUMBER: _ClassVar[int]
    TAG_NAME_FIELD_NUMBER: _ClassVar[int]
    TIME_DELAY_S_FIELD_NUMBER: _ClassVar[int]
    TRANSITION_SPEED_PCT_FIELD_NUMBER: _ClassVar[int]
    accel_pct: float
    aux_commands: _containers.RepeatedScalarFieldContainer[str]
    joints: _containers.RepeatedScalarFieldContainer[float]
    pose: _containers.RepeatedScalarFieldContainer[float]
    speed_pct: float
    tag_index: int
    tag_name: str
    time_delay_s: float
    transition_speed_pct: float
    def __init__(self, pose: _Optional[_Iterable[float]] = ..., joints: _Optional[_Iterable[float]] = ..., tag_name: _Optional[str] = ..., tag_index: _Optional[int] = ..., time_delay_s: _Optional[float] = ..., transition_speed_pct: _Optional[float] = ..., speed_pct: _Optional[float] = ..., accel_pct: _Optional[float] = ..., aux_commands: _Optional[_Iterable[str]] = ...) -> None: ...

class Uplink(_message.Message):
    __slots__ = ["mac", "request", "rsvp_reply"]
    MAC_FIELD_NUMBER: _ClassVar[int]
    REQUEST_FIELD_NUMBER: _ClassVar[int]
    RSVP_REPLY_FIELD_NUMBER: _ClassVar[int]
    mac: bytes
    request: Request
    rsvp_reply: RsvpReply
    def __init__(self, request: _Optional[_Union[Request, _Mapping]] = ..., rsvp_reply: _Optional[_Union[RsvpReply, _Mapping]] = ..., mac: _Optional[bytes] = ...) -> None: ...

class Protocol(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class IsotpId(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class IsotpParam(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class HeartbeatPeriod(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class NodeAddress(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class State(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class RetCode(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class AuthPolicy(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class AuthParam(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class OffsetType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class ReferenceFrame(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class MotionType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class SpeedType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class AccelType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class LinearUnit(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class AngularUnit(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class MotionEnd(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class CallbackType(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class DisconnectAction(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class HomeState(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class NoticeKind(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []

class EventId(int, metaclass=_enum_type_wrapper.EnumTypeWrapper):
    __slots__ = []
