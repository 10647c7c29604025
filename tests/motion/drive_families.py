#!/usr/bin/python3
"""Two single-axis drives of one family on one Modbus line, X at unit 1 and Y
at unit 2, each following its manual's semantics as the family's profile
header states them, for tests/motion/drive_families_test.cpp. Written with
Debian's pymodbus (python3-pymodbus 3.0, run with /usr/bin/python3).

--family pcon: an IAI PCON (profile config/benches/iai_pcon_two_axes.toml,
  IAI manual ME0162). Holding registers only, 32-bit values upper word first.
  DRG1 0D00h acts on levels and rising edges: SON (bit 12) level, the servo
  (SV, DSS1 bit 12) on 100 ms after it; HOME (bit 4) rising: home return at
  20 mm/s to 0 mm, HEND (DSS1 bit 4) dropped at the start and set at the end;
  CSTR (bit 3) rising: positioning to position table No. POSR (0D03h; only
  No. 0, at 1000h: PCMD 1000h-1001h in 0.01 mm, VCMD 1004h-1005h in
  0.01 mm/s), PEND (DSS1 bit 3) dropped at the start and set once the
  actuator is at the target with CSTR released again, MOVE (DSSE 9007h bit 5)
  while it moves; STP (bit 5) level: pause (decelerate, hold; the remaining
  travel resumes when STP drops); ALRS (bit 8) rising: alarm reset, and while
  paused, the remaining travel is cancelled. Alarms (ALMC 9002h, ALMH DSS1
  bit 10; the actuator stops): 080h a move or home return with the servo
  off, 083h positioning before home return completed, 085h a position No.
  other than 0. The PCON's own soft limits are not emulated (the bench's
  soft limits keep every target inside the stroke).
--family az: an Oriental Motor AZ driver (profile
  config/benches/oriental_az_two_axes.toml, manual HM-60262). Holding
  registers, 32-bit values upper word first. Driver input command 007Ch-007Dh
  (lower word: R-IN0..15) acts on rising edges: START (R-IN3) positioning of
  operation data No. M0-M2 (only No. 0: type 1800h-1801h, 1 = absolute
  positioning, position 1802h-1803h in steps, speed 1804h-1805h in Hz);
  ZHOME (R-IN4) return to home at 10 kHz to 0 steps, HOME-END (R-OUT4)
  dropped at the start and set at the end; STOP (R-IN5) stops and cancels
  the operation, and no operation starts while it is on; ALM-RST (R-IN7)
  resets an alarm. Excitation is on from power-up (FREE, R-IN6, off).
  Driver output status 007Eh-007Fh: HOME-END R-OUT4, READY R-OUT5, ALM-A
  R-OUT7, MOVE R-OUT13, IN-POS R-OUT14 (dropped at START, set at the end of
  positioning), R-OUT15 ETO-MON (reassigned, as the profile asks). Present
  alarm 0080h-0081h; feedback position 00CCh-00CDh, steps. Alarms: 4Ah
  positioning started before the origin was set, 67h a target beyond the
  software limits (0 .. --stroke-mm), 70h an operation type other than 1.

Both: the drives power up at 5 mm, not homed. The motion is a constant-speed
ramp in whole counts computed from the clock, so a settled position is the
target count exactly.

Faults: --refuse-target-writes UNIT: that unit answers every write to its
target registers with exception 04 (slave device failure), as a drive that
refuses the data; the rest of its map works. SIGUSR1 raises the Y drive's
overload alarm (PCON 0E0h, AZ 30h) and stops it, as a jammed axis would.

Links: --tcp (default): Modbus TCP on an ephemeral port of 127.0.0.1, first
line printed "PORT <n>"; --rtu DEVICE [--baud B --parity N|E|O --stop 1|2]:
Modbus RTU on a serial device (one end of a socat pty pair: use --parity N
there, pyserial cannot set parity on a pty, which carries bytes whatever its
settings), first line "READY". A unit other than 1 and 2 gets no answer. SIGTERM or SIGINT stops it.
"""
import argparse
import asyncio
import logging
import signal
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server.async_io import ModbusSerialServer, ModbusTcpServer
from pymodbus.transaction import ModbusRtuFramer

COUNTS_PER_MM = 100  # PCON: 0.01 mm; AZ: 100 steps/mm on the profile's mechanics
START_MM = 5


class Ramp:
    """A constant-speed move in whole counts, computed from the clock."""

    def __init__(self, counts):
        self.start = self.target = counts
        self.t0, self.speed = 0.0, 1.0

    def at(self, now):
        span = self.target - self.start
        if span == 0:
            return self.target
        return round(self.start + span * min(1.0, (now - self.t0) * self.speed / abs(span)))

    def moving(self, now):
        return self.at(now) != self.target

    def go(self, now, target, speed):
        self.start, self.target, self.t0, self.speed = self.at(now), target, now, max(speed, 1)

    def halt(self, now):
        self.go(now, self.at(now), self.speed)


def words(value):
    """A signed 32-bit value as two registers, upper word first."""
    u = value & 0xFFFFFFFF
    return [u >> 16, u & 0xFFFF]


def value_of(regs):
    u = (regs[0] << 16) | regs[1]
    return u - (1 << 32) if u & 0x80000000 else u


class Drive(ModbusSequentialDataBlock):
    """The holding registers of one drive; subclasses give the semantics."""

    TARGET = 0  # first of the two target registers, for --refuse-target-writes

    def __init__(self, stroke_mm):
        super().__init__(0, [0] * 0x10000)
        self.axis = Ramp(START_MM * COUNTS_PER_MM)
        self.stroke = round(stroke_mm * COUNTS_PER_MM)
        self.refuse_target = False
        self.alarm = 0

    def reg(self, address, count=1):
        return super().getValues(address, count)

    def put(self, address, values):
        super().setValues(address, values)

    def getValues(self, address, count=1):
        self.refresh(time.monotonic())
        return super().getValues(address, count)

    def setValues(self, address, values):
        values = values if isinstance(values, list) else [values]
        if self.refuse_target and address <= self.TARGET + 1 and self.TARGET < address + len(values):
            raise ValueError("target write refused")  # answered with exception 04
        self.written(time.monotonic(), address, values)

    def trip(self, now, code):
        """An alarm: the actuator stops where it is."""
        self.alarm = code
        self.axis.halt(now)


class Pcon(Drive):
    DRG1, POSR = 0x0D00, 0x0D03
    PCMD, VCMD = 0x1000, 0x1004  # position table No. 0
    PNOW, ALMC, DSS1, DSSE = 0x9000, 0x9002, 0x9005, 0x9007
    SON, ALRS, STP, HOME, CSTR = 1 << 12, 1 << 8, 1 << 5, 1 << 4, 1 << 3
    SV, ALMH, HEND, PEND, PWR = 1 << 12, 1 << 10, 1 << 4, 1 << 3, 1 << 13
    MOVE = 1 << 5  # in DSSE
    TARGET = PCMD
    SERVO_DELAY_S = 0.1
    HOME_SPEED = 20 * COUNTS_PER_MM  # counts/s
    SERVO_OFF, NOT_HOMED, POSITION_NO = 0x080, 0x083, 0x085
    OVERLOAD = 0x0E0

    def __init__(self, stroke_mm):
        super().__init__(stroke_mm)
        self.servo_since = None
        self.homed = self.homing = False
        self.goal = None  # target of the positioning or home return in progress or done
        self.remaining = None  # target of a paused positioning, None once cancelled

    def servo_ready(self, now):
        return self.servo_since is not None and now - self.servo_since >= self.SERVO_DELAY_S

    def refresh(self, now):
        pos, moving = self.axis.at(now), self.axis.moving(now)
        if self.homing and not moving and pos == 0:
            self.homing, self.homed = False, True
        drg1 = self.reg(self.DRG1)[0]
        dss1 = self.PWR | (self.SV if self.servo_ready(now) else 0)
        dss1 |= self.HEND if self.homed else 0
        dss1 |= self.ALMH if self.alarm else 0
        dss1 |= self.STP if drg1 & self.STP else 0
        if (self.goal == pos and not moving and not self.alarm and self.servo_ready(now)
                and not drg1 & self.CSTR and not self.homing):
            dss1 |= self.PEND
        self.put(self.PNOW, words(pos) + [self.alarm])
        self.put(self.DSS1, [dss1, 0, self.MOVE if moving else 0])

    def written(self, now, address, values):
        old = self.reg(self.DRG1)[0]
        self.put(address, values)
        if address <= self.DRG1 < address + len(values):
            self.control(now, old, values[self.DRG1 - address])

    def control(self, now, old, new):
        rise = new & ~old
        if new & self.SON and self.servo_since is None:
            self.servo_since = now
        elif not new & self.SON and self.servo_since is not None:
            self.servo_since = None
            self.axis.halt(now)
        if rise & self.STP:  # pause: decelerate and hold the rest of the travel
            self.remaining = self.axis.target if self.axis.moving(now) else None
            self.axis.halt(now)
        if rise & self.ALRS:
            if new & self.STP:
                self.remaining = None  # reset while paused cancels the remaining travel
                self.goal = None
            self.alarm = 0
        if old & self.STP and not new & self.STP and self.remaining is not None:
            self.axis.go(now, self.remaining, self.axis.speed)
            self.remaining = None
        if new & self.STP or self.alarm:
            return
        if rise & self.HOME:
            self.home(now)
        elif rise & self.CSTR:
            self.position(now)

    def home(self, now):
        if not self.servo_ready(now):
            self.trip(now, self.SERVO_OFF)
            return
        self.homed, self.homing, self.goal = False, True, 0
        self.axis.go(now, 0, self.HOME_SPEED)

    def position(self, now):
        if not self.servo_ready(now):
            self.trip(now, self.SERVO_OFF)
        elif not self.homed:
            self.trip(now, self.NOT_HOMED)
        elif self.reg(self.POSR)[0] != 0:
            self.trip(now, self.POSITION_NO)
        else:
            self.goal = value_of(self.reg(self.PCMD, 2))
            self.axis.go(now, self.goal, value_of(self.reg(self.VCMD, 2)))


class Az(Drive):
    INPUT, OUTPUT, ALARM, FEEDBACK = 0x007C, 0x007E, 0x0080, 0x00CC
    OP_TYPE, OP_POS, OP_SPEED = 0x1800, 0x1802, 0x1804  # operation data No. 0
    M_BITS, START, ZHOME, STOP, FREE, ALM_RST = 0x7, 1 << 3, 1 << 4, 1 << 5, 1 << 6, 1 << 7
    HOME_END, READY, ALM_A, MOVE, IN_POS = 1 << 4, 1 << 5, 1 << 7, 1 << 13, 1 << 14
    TARGET = OP_POS
    HOME_SPEED = 10000  # Hz = steps/s
    ABSOLUTE = 1
    NOT_HOMED, SOFT_OVERTRAVEL, BAD_DATA, OVERLOAD = 0x4A, 0x67, 0x70, 0x30

    def __init__(self, stroke_mm):
        super().__init__(stroke_mm)
        self.homed = self.homing = False
        self.goal = None
        self.put(self.OP_TYPE, words(self.ABSOLUTE))

    def refresh(self, now):
        pos, moving = self.axis.at(now), self.axis.moving(now)
        if self.homing and not moving and pos == 0:
            self.homing, self.homed = False, True
        r_in = self.reg(self.INPUT + 1)[0]
        out = (self.HOME_END if self.homed else 0) | (self.MOVE if moving else 0)
        out |= self.ALM_A if self.alarm else 0
        if not moving and not self.alarm and not r_in & self.STOP:
            out |= self.READY
        if self.goal == pos and not moving and not self.alarm and not self.homing:
            out |= self.IN_POS
        self.put(self.OUTPUT, [0, out, 0, self.alarm])
        self.put(self.FEEDBACK, words(pos))

    def written(self, now, address, values):
        old = self.reg(self.INPUT + 1)[0]
        self.put(address, values)
        if address <= self.INPUT + 1 < address + len(values):
            self.control(now, old, values[self.INPUT + 1 - address])

    def control(self, now, old, new):
        rise = new & ~old
        if rise & self.ALM_RST:
            self.alarm = 0
        if rise & self.STOP:
            self.axis.halt(now)
            self.goal = None
        if new & (self.STOP | self.FREE) or self.alarm:
            return
        if rise & self.ZHOME:
            self.homed, self.homing, self.goal = False, True, 0
            self.axis.go(now, 0, self.HOME_SPEED)
        elif rise & self.START:
            self.start(now, new & self.M_BITS)

    def start(self, now, number):
        target = value_of(self.reg(self.OP_POS, 2))
        if number != 0 or value_of(self.reg(self.OP_TYPE, 2)) != self.ABSOLUTE:
            self.trip(now, self.BAD_DATA)
        elif not self.homed:
            self.trip(now, self.NOT_HOMED)
        elif not 0 <= target <= self.stroke:
            self.trip(now, self.SOFT_OVERTRAVEL)
        else:
            self.goal = target
            self.axis.go(now, target, value_of(self.reg(self.OP_SPEED, 2)))


async def serve(args, context):
    if args.rtu:
        server = ModbusSerialServer(context, framer=ModbusRtuFramer, port=args.rtu,
                                    baudrate=args.baud, parity=args.parity,
                                    stopbits=args.stop, bytesize=8, ignore_missing_slaves=True)
        await server.start()
        asyncio.create_task(server.serve_forever())
        print("READY", flush=True)
        return server
    server = ModbusTcpServer(context, address=("127.0.0.1", 0), allow_reuse_address=True,
                             ignore_missing_slaves=True)
    asyncio.create_task(server.serve_forever())
    await server.serving
    print("PORT", server.server.sockets[0].getsockname()[1], flush=True)
    return server


async def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--family", choices=["pcon", "az"], required=True)
    parser.add_argument("--stroke-mm", type=float, default=300)
    parser.add_argument("--refuse-target-writes", type=int, default=0, metavar="UNIT")
    parser.add_argument("--rtu", metavar="DEVICE")
    parser.add_argument("--baud", type=int, default=115200)
    parser.add_argument("--parity", choices=["N", "E", "O"], default="E")
    parser.add_argument("--stop", type=int, choices=[1, 2], default=1)
    args = parser.parse_args()
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    family = Pcon if args.family == "pcon" else Az
    drives = {1: family(args.stroke_mm), 2: family(args.stroke_mm)}
    if args.refuse_target_writes in drives:
        drives[args.refuse_target_writes].refuse_target = True
    context = ModbusServerContext(
        slaves={u: ModbusSlaveContext(hr=d, zero_mode=True) for u, d in drives.items()},
        single=False)
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    loop.add_signal_handler(signal.SIGUSR1,
                            lambda: drives[2].trip(time.monotonic(), family.OVERLOAD))
    server = await serve(args, context)
    await stop.wait()
    await server.shutdown()


if __name__ == "__main__":
    asyncio.run(main())
