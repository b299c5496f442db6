"""One sample of every message, shared by the codec tests and the golden vectors."""

from protocol import messages as m
from protocol.constants import (
    CFG_CORRUPT,
    E_LATCHED,
    EV_TRIP,
    F_OVERLOAD,
    F_SHORT,
    RESET_WATCHDOG,
    ST_INRUSH,
    ST_LATCHED,
    ST_OFF,
    ST_ON,
    ST_TRIPPED,
)
from tests.protocol.util import NONCE


def channel_config(cls: type = m.ChannelConfig, req_id: int = 0) -> m.Message:
    return cls(
        channel=3,
        name="hokuyo",
        rated_ma=700,
        inrush_ms=100,
        inrush_factor_x10=40,
        trip_factor_x10=30,
        trip_samples=2,
        overload_start_x100=110,
        i2t_ms=3100,
        retry_reset_ms=60000,
        short_retries=1,
        open_load_ma=0,
        open_load_ms=1000,
        stuck_on_ma=50,
        stuck_on_ms=200,
        powerup=True,
        priority=30,
        protected=False,
        retry_ms=[1000, 2000, 5000],
        req_id=req_id,
    )


def board_config(cls: type = m.BoardConfig, req_id: int = 0) -> m.Message:
    return cls(
        total_limit_ma=20000,
        uv_warn_mv=22000,
        uv_shed_mv=21000,
        uv_off_mv=20000,
        uv_hyst_mv=500,
        tick_ms=10,
        powerup_spacing_ms=200,
        deadman_ms=0,
        deadman_on_mask=0x0004,
        modbus_write=False,
        board_id="tedusar",
        modbus_allow=[0x7F000001],
        req_id=req_id,
    )


def samples() -> "list[m.Message]":
    """Every message type once, with a request id and plausible values."""
    cs = m.ChannelStatus
    return [
        m.Hello(1, "tedusar", "0.1.0", 10, 0x007F, 0xC0FFEE01, NONCE, RESET_WATCHDOG, CFG_CORRUPT),
        m.HelloRequest(req_id=1),
        m.Ping(0xDEADBEEF, req_id=2),
        m.Pong(0xDEADBEEF, 61234, req_id=2),
        m.GetState(req_id=3),
        m.State(
            61250,
            24100,
            3210,
            RESET_WATCHDOG,
            CFG_CORRUPT,
            0,
            [
                cs(
                    channel=0,
                    commanded=True,
                    physical=True,
                    state=ST_ON,
                    current_ma=1510,
                    live_faults=0,
                    sticky_faults=0,
                    trips=0,
                    retries=0,
                ),
                cs(
                    channel=1,
                    commanded=True,
                    physical=False,
                    state=ST_TRIPPED,
                    current_ma=-3,
                    live_faults=F_OVERLOAD,
                    sticky_faults=F_OVERLOAD,
                    trips=2,
                    retries=2,
                ),
                cs(
                    channel=2,
                    commanded=False,
                    physical=False,
                    state=ST_LATCHED,
                    current_ma=0,
                    live_faults=0,
                    sticky_faults=F_SHORT,
                    trips=2,
                    retries=1,
                ),
            ],
            req_id=3,
        ),
        m.Subscribe(100, req_id=4),
        m.Measurement(17, 61260, 24090, 0x0089, 0x0002, [1510, -3, 0, 702, 0, 0, 0, 4980, 0, 0]),
        m.Event(5, 61261, EV_TRIP, 1, ST_ON, ST_TRIPPED, F_OVERLOAD, 1410, 0),
        m.Switch(3, True, False, req_id=5),
        m.Switched(3, True, True, ST_INRUSH, req_id=5),
        m.PowerCycle(7, 2000, False, req_id=6),
        m.Clear(2, req_id=7),
        m.GetConfig(3, req_id=8),
        channel_config(m.ChannelConfig, 8),
        channel_config(m.SetChannelConfig, 9),
        m.GetConfig(0xFF, req_id=10),
        board_config(m.BoardConfig, 10),
        board_config(m.SetBoardConfig, 11),
        m.SaveConfig(req_id=12),
        m.Reboot(req_id=13),
        m.Ack(0x35, req_id=12),
        m.Error(E_LATCHED, 0x20, "channel latched: clear it first", req_id=14),
        m.Switched(2, False, False, ST_OFF, req_id=7),
    ]


def later_samples() -> "list[m.Message]":
    """Messages (and optional fields) added after the first vectors: last in golden.json."""
    return [
        m.AuthPing(0xC0FFEE, req_id=30),
        m.Subscribe(100, per_frame=4, req_id=31),
        m.MeasurementBatch([
            m.Measurement(17, 61260, 24090, 0x0089, 0x0002,
                          [1510, -3, 0, 702, 0, 0, 0, 4980, 0, 0]),
            m.Measurement(18, 61270, 24085, 0x0089, 0x0002,
                          [1498, -3, 0, 711, 0, 0, 0, 5012, 0, 0]),
        ]),
    ]
