from google.protobuf.internal import containers as _containers
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from typing import ClassVar as _ClassVar, Iterable as _Iterable, Mapping as _Mapping, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Vector3(_message.Message):
    __slots__ = ("x", "y", "z")
    X_FIELD_NUMBER: _ClassVar[int]
    Y_FIELD_NUMBER: _ClassVar[int]
    Z_FIELD_NUMBER: _ClassVar[int]
    x: float
    y: float
    z: float
    def __init__(self, x: _Optional[float] = ..., y: _Optional[float] = ..., z: _Optional[float] = ...) -> None: ...

class BodyMotion(_message.Message):
    __slots__ = ("vel", "angvel")
    VEL_FIELD_NUMBER: _ClassVar[int]
    ANGVEL_FIELD_NUMBER: _ClassVar[int]
    vel: Vector3
    angvel: Vector3
    def __init__(self, vel: _Optional[_Union[Vector3, _Mapping]] = ..., angvel: _Optional[_Union[Vector3, _Mapping]] = ...) -> None: ...

class JointState(_message.Message):
    __slots__ = ("position", "velocity", "motor_force")
    POSITION_FIELD_NUMBER: _ClassVar[int]
    VELOCITY_FIELD_NUMBER: _ClassVar[int]
    MOTOR_FORCE_FIELD_NUMBER: _ClassVar[int]
    position: float
    velocity: float
    motor_force: float
    def __init__(self, position: _Optional[float] = ..., velocity: _Optional[float] = ..., motor_force: _Optional[float] = ...) -> None: ...

class ContactPair(_message.Message):
    __slots__ = ("a", "b", "points", "depth", "normal_force")
    A_FIELD_NUMBER: _ClassVar[int]
    B_FIELD_NUMBER: _ClassVar[int]
    POINTS_FIELD_NUMBER: _ClassVar[int]
    DEPTH_FIELD_NUMBER: _ClassVar[int]
    NORMAL_FORCE_FIELD_NUMBER: _ClassVar[int]
    a: str
    b: str
    points: int
    depth: float
    normal_force: float
    def __init__(self, a: _Optional[str] = ..., b: _Optional[str] = ..., points: _Optional[int] = ..., depth: _Optional[float] = ..., normal_force: _Optional[float] = ...) -> None: ...

class Contacts(_message.Message):
    __slots__ = ("count", "pairs")
    COUNT_FIELD_NUMBER: _ClassVar[int]
    PAIRS_FIELD_NUMBER: _ClassVar[int]
    count: int
    pairs: _containers.RepeatedCompositeFieldContainer[ContactPair]
    def __init__(self, count: _Optional[int] = ..., pairs: _Optional[_Iterable[_Union[ContactPair, _Mapping]]] = ...) -> None: ...

class KeyValue(_message.Message):
    __slots__ = ("key", "value")
    KEY_FIELD_NUMBER: _ClassVar[int]
    VALUE_FIELD_NUMBER: _ClassVar[int]
    key: str
    value: str
    def __init__(self, key: _Optional[str] = ..., value: _Optional[str] = ...) -> None: ...

class Event(_message.Message):
    __slots__ = ("time", "name", "source", "detail")
    TIME_FIELD_NUMBER: _ClassVar[int]
    NAME_FIELD_NUMBER: _ClassVar[int]
    SOURCE_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    time: float
    name: str
    source: str
    detail: _containers.RepeatedCompositeFieldContainer[KeyValue]
    def __init__(self, time: _Optional[float] = ..., name: _Optional[str] = ..., source: _Optional[str] = ..., detail: _Optional[_Iterable[_Union[KeyValue, _Mapping]]] = ...) -> None: ...

class Sound(_message.Message):
    __slots__ = ("time", "name", "action", "offset", "volume")
    TIME_FIELD_NUMBER: _ClassVar[int]
    NAME_FIELD_NUMBER: _ClassVar[int]
    ACTION_FIELD_NUMBER: _ClassVar[int]
    OFFSET_FIELD_NUMBER: _ClassVar[int]
    VOLUME_FIELD_NUMBER: _ClassVar[int]
    time: float
    name: str
    action: str
    offset: float
    volume: float
    def __init__(self, time: _Optional[float] = ..., name: _Optional[str] = ..., action: _Optional[str] = ..., offset: _Optional[float] = ..., volume: _Optional[float] = ...) -> None: ...

class Verdict(_message.Message):
    __slots__ = ("name", "kind", "passed", "measured", "expected", "time", "message", "value", "target", "tolerance", "known_limit")
    NAME_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    PASSED_FIELD_NUMBER: _ClassVar[int]
    MEASURED_FIELD_NUMBER: _ClassVar[int]
    EXPECTED_FIELD_NUMBER: _ClassVar[int]
    TIME_FIELD_NUMBER: _ClassVar[int]
    MESSAGE_FIELD_NUMBER: _ClassVar[int]
    VALUE_FIELD_NUMBER: _ClassVar[int]
    TARGET_FIELD_NUMBER: _ClassVar[int]
    TOLERANCE_FIELD_NUMBER: _ClassVar[int]
    KNOWN_LIMIT_FIELD_NUMBER: _ClassVar[int]
    name: str
    kind: str
    passed: bool
    measured: str
    expected: str
    time: float
    message: str
    value: float
    target: float
    tolerance: float
    known_limit: KnownLimit
    def __init__(self, name: _Optional[str] = ..., kind: _Optional[str] = ..., passed: bool = ..., measured: _Optional[str] = ..., expected: _Optional[str] = ..., time: _Optional[float] = ..., message: _Optional[str] = ..., value: _Optional[float] = ..., target: _Optional[float] = ..., tolerance: _Optional[float] = ..., known_limit: _Optional[_Union[KnownLimit, _Mapping]] = ...) -> None: ...

class KnownLimit(_message.Message):
    __slots__ = ("measured", "cause", "doc")
    MEASURED_FIELD_NUMBER: _ClassVar[int]
    CAUSE_FIELD_NUMBER: _ClassVar[int]
    DOC_FIELD_NUMBER: _ClassVar[int]
    measured: float
    cause: str
    doc: str
    def __init__(self, measured: _Optional[float] = ..., cause: _Optional[str] = ..., doc: _Optional[str] = ...) -> None: ...

class Verdicts(_message.Message):
    __slots__ = ("time", "verdicts")
    TIME_FIELD_NUMBER: _ClassVar[int]
    VERDICTS_FIELD_NUMBER: _ClassVar[int]
    time: float
    verdicts: _containers.RepeatedCompositeFieldContainer[Verdict]
    def __init__(self, time: _Optional[float] = ..., verdicts: _Optional[_Iterable[_Union[Verdict, _Mapping]]] = ...) -> None: ...
