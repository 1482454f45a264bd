"""The independent reference for hand-canopen: python `canopen` (2.4.x).

Run by canopen/tests/canopen_reference.rs over stdin/stdout:

1. One JSON line in: the EDS path, the node id and our tables (object dictionary of the
   simulated drive, abort codes, EMCY classes, statusword decoding, the CiA 402 transitions).
   `canopen` parses the EDS (which checks the file) and its own tables are compared with ours;
   one JSON line out with every disagreement.
2. Then a frame exchange with a `canopen.LocalNode` built from the EDS. Lines in:
   `F <t_us> <id hex> <data hex>` (a frame on the bus), `T <t_us>` (time passes),
   `Q` (quit: one JSON summary line out). After each F/T line: the frames the drive sent,
   `F <id hex> <data hex>`, then a line `.`.

LocalNode is an SDO server over an object dictionary with NMT state tracking. What a CiA 402
drive does beyond that is scripted here, around it, from canopen's own CiA 402 tables
(`State402`): boot-up after an NMT reset, the power state machine on controlword writes,
RPDOs applied to the dictionary and TPDOs sent on SYNC, the heartbeat producer, and the
0x1016 consumer with the 0x6007 / 0x605A reaction.
"""

import json
import struct
import sys

import canopen
from canopen.emcy import EmcyError
from canopen.objectdictionary import ODVariable
from canopen.profiles.p402 import State402
from canopen.sdo.exceptions import SdoAbortedError

SIGNED = {0x2, 0x3, 0x4}
INTERNAL = {"START", "NOT READY TO SWITCH ON", "FAULT REACTION ACTIVE"}

EMCY_CLASS_NAMES = {
    "NoError": "Error Reset / No Error",
    "Generic": "Generic Error",
    "Current": "Current",
    "Voltage": "Voltage",
    "Temperature": "Temperature",
    "Hardware": "Device Hardware",
    "Software": "Device Software",
    "AdditionalModules": "Additional Modules",
    "Monitoring": "Monitoring",
    "External": "External Error",
    "AdditionalFunctions": "Additional Functions",
    "DeviceSpecific": "Device Specific",
    "Reserved": "",
}


def entry(od, index, sub):
    obj = od[index]
    if isinstance(obj, ODVariable):
        return obj if sub == 0 else None
    return obj[sub] if sub in obj else None


def compare_tables(od, init):
    bad = []
    checked = {}
    # Our simulated drive's dictionary against the EDS as canopen read it.
    ours = set()
    for index, sub, size, signed, access, mappable, default in init["objects"]:
        ours.add((index, sub))
        var = entry(od, index, sub) if index in od else None
        name = f"0x{index:04X}:{sub:02X}"
        if var is None:
            bad.append(f"{name} in the Rust table, not in the EDS")
            continue
        if len(var) // 8 != size:
            bad.append(f"{name}: {size} bytes in Rust, {len(var)} bits in the EDS")
        if (var.data_type in SIGNED) != signed:
            bad.append(f"{name}: signedness differs (EDS type 0x{var.data_type:X})")
        if var.access_type != access:
            bad.append(f"{name}: access {access} in Rust, {var.access_type} in the EDS")
        if bool(var.pdo_mappable) != mappable:
            bad.append(f"{name}: PDO mapping {mappable} in Rust, {var.pdo_mappable} in the EDS")
        if signed and default >= 1 << (8 * size - 1):
            default -= 1 << (8 * size)
        if var.default != default:
            bad.append(f"{name}: default {default} in Rust, {var.default} in the EDS")
    eds = set()
    for index in od:
        obj = od[index]
        if isinstance(obj, ODVariable):
            eds.add((index, 0))
        else:
            eds.update((index, s) for s in obj.subindices)
    for index, sub in sorted(eds - ours):
        bad.append(f"0x{index:04X}:{sub:02X} in the EDS, not in the Rust table")
    checked["objects"] = len(ours)

    # Abort codes: every code canopen names must be named by us.
    named = {code for code, name in init["abort_codes"] if name != "Other"}
    for code in SdoAbortedError.CODES:
        if code not in named:
            bad.append(f"abort code 0x{code:08X} ({SdoAbortedError.CODES[code]}) not named in Rust")
    checked["abort_codes"] = len(SdoAbortedError.CODES)

    # EMCY classes: where canopen names a class, ours must be the same.
    blank = 0
    for code, cls in init["emcy"]:
        desc = EmcyError(code, 0, b"", 0.0).get_desc()
        if desc == "":
            blank += 1
            continue
        if EMCY_CLASS_NAMES.get(cls) != desc:
            bad.append(f"EMCY 0x{code:04X}: class {cls} in Rust, '{desc}' in canopen")
    checked["emcy_codes"] = len(init["emcy"])
    checked["emcy_codes_canopen_leaves_unnamed"] = blank

    # Statusword decoding against State402.SW_MASK.
    for sw, state in init["statuswords"]:
        theirs = None
        for name, (mask, value) in State402.SW_MASK.items():
            if sw & mask == value:
                theirs = name
                break
        if theirs != (state.upper() if state else None):
            bad.append(f"statusword 0x{sw:04X}: {state} in Rust, {theirs} in canopen")
    checked["statuswords"] = len(init["statuswords"])

    # Transitions: every (from, to) of ours is in canopen's table, and one of our
    # controlwords for it is canopen's.
    pairs = {}
    for frm, cw, to in init["transitions"]:
        pairs.setdefault((frm.upper(), to.upper()), set()).add(cw)
    for (frm, to), cws in pairs.items():
        code = State402.TRANSITIONTABLE.get((frm, to))
        if code is None:
            bad.append(f"transition {frm} -> {to} not in canopen's table")
        elif code not in cws:
            bad.append(f"transition {frm} -> {to}: canopen 0x{code:04X}, Rust {sorted(cws)}")
    checked["transitions"] = len(pairs)
    return {"mismatches": bad, "checked": checked}


class NoTask:
    def stop(self):
        pass

    def update(self, data):
        pass


class Drive:
    def __init__(self, node_id, od):
        self.id = node_id
        self.node = canopen.LocalNode(node_id, od)
        self.net = canopen.Network()
        self.out = []
        self.net.send_message = lambda cid, data, remote=False: self.out.append((cid, bytes(data)))
        self.net.send_periodic = lambda *a, **k: NoTask()
        self.net.add_node(self.node)
        self.net.subscribe(0, self.on_nmt)
        self.sync_cob = 0x80
        self.net.subscribe(self.sync_cob, self.on_sync)
        self.node.add_write_callback(self.on_write)
        self.cw = 0
        self.quick_stops = 0
        self.watchdog_trips = 0
        self.master_seen = None
        self.next_hb = 0
        self.now = 0
        self.pending = {}
        self.rpdo_len_errors = 0
        self.set_state("SWITCH ON DISABLED")

    def u(self, index, sub=0):
        var = entry(self.node.object_dictionary, index, sub)
        return var.decode_raw(self.node.get_data(index, sub))

    def set_state(self, state):
        if state == "QUICK STOP ACTIVE" and getattr(self, "state", None) != state:
            self.quick_stops += 1
        self.state = state
        self.node.data_store.setdefault(0x6041, {})[0] = struct.pack("<H", State402.SW_MASK[state][1])

    def on_write(self, index, subindex, od, data):
        if index == 0x1005:
            # The SYNC COB-ID (CiA 301): SYNC is taken on the id written here from now on.
            cob = struct.unpack("<I", data)[0] & 0x7FF
            if cob != self.sync_cob:
                self.net.unsubscribe(self.sync_cob, self.on_sync)
                self.sync_cob = cob
                self.net.subscribe(cob, self.on_sync)
        elif index == 0x6040:
            prev, self.cw = self.cw, struct.unpack("<H", data)[0]
            for (frm, to), code in State402.TRANSITIONTABLE.items():
                if frm != self.state or frm in INTERNAL or code != self.cw:
                    continue
                if code == State402.CW_SWITCH_ON_DISABLED and prev & 0x80:
                    continue  # fault reset needs a 0 -> 1 edge
                self.set_state(to)
                break

    def on_nmt(self, can_id, data, ts):
        cmd, node = data[0], data[1]
        if node not in (0, self.id):
            return
        if cmd in (0x81, 0x82):
            for index in list(self.node.data_store):
                if cmd == 0x81 or 0x1000 <= index < 0x2000:
                    del self.node.data_store[index]
            if cmd == 0x81:
                self.set_state("SWITCH ON DISABLED")
            self.master_seen = None
            self.pending.clear()
            self.out.append((0x700 + self.id, b"\x00"))
            self.node.nmt._state = 127
        elif cmd == 0x01:
            # Operational: take the PDO configuration the master wrote.
            self.node.rpdo.read()
            self.node.tpdo.read()

    def rpdo_maps(self):
        return [m for m in self.node.rpdo.map.values() if m.enabled]

    def on_frame(self, can_id, data):
        hb = self.u(0x1016, 1)
        if hb and can_id == 0x700 + ((hb >> 16) & 0x7F):
            self.master_seen = self.now
        if self.node.nmt._state == 5:
            for m in self.rpdo_maps():
                if m.cob_id == can_id:
                    if len(data) != m.length // 8:
                        self.rpdo_len_errors += 1
                        self.node.emcy.send(0x8210, 0x10)
                    else:
                        self.pending[can_id] = (m, bytes(data))

    def on_sync(self, can_id, data, ts):
        if self.node.nmt._state != 5:
            return
        for m, payload in self.pending.values():
            m.data = bytearray(payload)
            for var in m:
                self.node.set_data(var.index, var.subindex, var.get_data())
        self.pending.clear()
        if self.state == "OPERATION ENABLED":
            mode = self.u(0x6060)
            if mode == 10:
                self.node.data_store.setdefault(0x6077, {})[0] = self.node.get_data(0x6071, 0)
            elif mode in (3, 9):
                self.node.data_store.setdefault(0x606C, {})[0] = self.node.get_data(0x60FF, 0)
        for m in self.node.tpdo.map.values():
            if m.enabled and m.trans_type is not None and 1 <= m.trans_type <= 240:
                for var in m:
                    var.set_data(self.node.get_data(var.index, var.subindex))
                m.transmit()

    def tick(self, now):
        self.now = now
        state = self.node.nmt._state
        period = self.u(0x1017)
        if period and state != 0 and now >= self.next_hb:
            self.next_hb = now + period * 1000
            self.out.append((0x700 + self.id, bytes([state])))
        hb = self.u(0x1016, 1)
        timeout_us = (hb & 0xFFFF) * 1000
        if self.master_seen is not None and timeout_us and now - self.master_seen > timeout_us:
            self.master_seen = None
            self.watchdog_trips += 1
            self.node.emcy.send(0x8130, 0x11)
            action = self.u(0x6007)
            if action == 3 and self.state == "OPERATION ENABLED":
                self.set_state("QUICK STOP ACTIVE")
            elif action == 2:
                self.set_state("SWITCH ON DISABLED")
            elif action == 1:
                self.set_state("FAULT")
        if self.state == "QUICK STOP ACTIVE" and 0 <= self.u(0x605A) <= 4:
            self.set_state("SWITCH ON DISABLED")

    def summary(self):
        def maps(pdo):
            pdo.read()
            return [
                {
                    "number": n,
                    "cob_id": m.cob_id,
                    "enabled": m.enabled,
                    "trans_type": m.trans_type,
                    "vars": [[v.index, v.subindex, v.length] for v in m],
                }
                for n, m in sorted(pdo.map.items())
            ]

        return {
            "state": self.state,
            "nmt": self.node.nmt.state,
            "quick_stops": self.quick_stops,
            "watchdog_trips": self.watchdog_trips,
            "rpdo_length_errors": self.rpdo_len_errors,
            "consumer_heartbeat": self.u(0x1016, 1),
            "mode": self.u(0x6060),
            "max_torque": self.u(0x6072),
            "rpdo": maps(self.node.rpdo),
            "tpdo": maps(self.node.tpdo),
        }


def main():
    init = json.loads(sys.stdin.readline())
    od = canopen.import_od(init["eds"], init["node"])
    print(json.dumps(compare_tables(od, init)), flush=True)
    drive = Drive(init["node"], od)
    for line in sys.stdin:
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "Q":
            print(json.dumps(drive.summary()), flush=True)
            return
        now = int(parts[1])
        if parts[0] == "F":
            can_id, data = int(parts[2], 16), bytes.fromhex(parts[3] if len(parts) > 3 else "")
            drive.now = now
            drive.on_frame(can_id, data)
            drive.net.notify(can_id, bytearray(data), now / 1e6)
        drive.tick(now)
        for cid, data in drive.out:
            print(f"F {cid:03X} {data.hex()}")
        drive.out.clear()
        print(".", flush=True)


if __name__ == "__main__":
    main()
