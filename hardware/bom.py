"""Generate each board revision's bill of materials (``bom.csv``) and its parts and limits page
(``board.md``) from the revision's file in ``firmware/boards`` (what the firmware boots: pins,
sense chip, addresses, shunt, divider) and the part data in ``hardware/parts.py`` (what is bought
around it), so that the parts list, the limits and the firmware cannot drift apart.

The limits are worked out, not typed: a channel's continuous current is the least of its
switch's rating, its sense chip's full scale over the shunt and its connector; its fuse and its
shunt's power rating follow from that (with the margins in ``parts.py``); the input range is the
narrowest of the switch, the sense chip's bus input, the ADC behind the divider, the regulator
and the surge stopper's clamp (its lowest, with the FB reference's and the divider's
tolerances). The clamp at its highest must stay under the absolute maximum of every part
behind the surge stopper, the TVS's clamp under the surge stopper's and its MOSFETs', and a
negative surge (``parts.REVERSE_SURGES``) held by the TVS above the surge stopper's reverse
rating: ``protection`` checks all three, and a revision that breaks one is refused (one line,
exit 2). The surge stopper's own support parts (``parts.STOPPER``) set its time-outs, its UV
and OV thresholds and the pass MOSFET's stress (``stopper``, from the LTC4364 data sheet's
figures in ``parts.LTC4364_TIMING``): a revision whose UV threshold could reach its lowest
input, whose OV threshold its highest, whose timer would run out before the bulk capacitor is
charged, or (once ``parts.py`` has the figure) whose MOSFET stress reaches its SOA, is refused
the same way.
Usage, from the repository root: ``python hardware/bom.py
[OUT_DIR]`` (default ``hardware``); ``tests/hardware/test_bom.py`` checks that the committed
files are its output. A revision that names a part ``parts.py`` lacks: one line saying what to
add, exit 2.
"""

from __future__ import annotations

import csv
import io
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

import parts as P  # noqa: E402 (hardware/ is put on the path first: these are scripts)
from pinmap import write  # noqa: E402

from protocol import settings  # noqa: E402

# the pass MOSFET's two worst cases, as board.md and the refusals name them
SHORTED, SURGE = "output shorted", "a surge held at the TVS's breakdown"
TRIP_FACTOR = next(d for name, _, d, _, _ in settings.CHANNEL if name == "trip_factor_x10") / 10


def clamp(b: dict[str, Any]) -> dict[str, Any]:
    """The surge stopper's output clamp: nominal, lowest and highest (the FB reference's and
    both divider resistors' tolerances), and its divider."""
    ss = P.INPUT["surge_stopper"]
    top_kohm = P.choices(b)["clamp_top_kohm"]
    ratio = top_kohm * 1000 / P.CLAMP_BOTTOM_OHM
    t = P.RESISTOR_TOL
    return {"top_kohm": top_kohm, "nominal": ss["fb_v"] * (1 + ratio),
            "low": ss["fb_v"] * (1 - ss["fb_tol"]) * (1 + ratio * (1 - t) / (1 + t)),
            "high": ss["fb_v"] * (1 + ss["fb_tol"]) * (1 + ratio * (1 + t) / (1 - t))}


def protected_parts(b: dict[str, Any]) -> list[tuple[str, float]]:
    """(part, absolute maximum voltage) of every part on the input rail behind the surge
    stopper: what its clamp must stay under."""
    c = P.choices(b)
    sw, sense, mcu = P.SWITCHES[c["switch"]], P.chip(b), P.MCU[b["mcu"]]
    out = [(f"the switch {sw['mpn']}", sw["abs_max_v"]),
           (f"the regulator {P.INPUT['regulator']['mpn']}", P.INPUT["regulator"]["abs_max_v"]),
           (f"the bulk capacitor {P.INPUT['bulk']['mpn']}", P.INPUT["bulk"]["abs_max_v"]),
           (f"the fuses' {P.FUSE_V:g} V rating", P.FUSE_V),
           ("the ADC behind the divider", mcu["adc_vref_v"] * b["vin"]["divider"])]
    if sense["mpn"] != sw["mpn"]:  # a smart switch senses itself: counted once
        out.insert(1, (f"the {sense['mpn']}", sense["abs_max_v"]))
    return out


def protection(b: dict[str, Any]) -> dict[str, Any]:
    """The input protection's numbers, checked: ``PartsError`` if the clamp at its highest
    reaches a protected part's absolute maximum, or the TVS's clamp the surge stopper's or
    its MOSFETs'."""
    cl = clamp(b)
    weakest = min(protected_parts(b), key=lambda p: p[1])
    if cl["high"] >= weakest[1]:
        raise P.PartsError(
            f"hardware/parts.py: {b['name']}'s surge stopper clamps at up to {cl['high']:.2f} V,"
            f" not under {weakest[0]}'s {weakest[1]:g} V absolute maximum; lower its "
            "clamp_top_kohm in REVISIONS")
    ss, fet, tvs = P.INPUT["surge_stopper"], P.INPUT["mosfet"], P.INPUT["tvs"]
    front = min((ss["abs_max_v"], f"the surge stopper {ss['mpn']}"),
                (fet["abs_max_v"], f"the {fet['mpn']} MOSFETs"))
    if tvs["clamp_v"] >= front[0]:
        raise P.PartsError(f"hardware/parts.py: the TVS {tvs['mpn']} clamps at "
                           f"{tvs['clamp_v']:g} V, not under the {front[0]:g} V of {front[1]}; "
                           "choose a lower TVS")
    reverse = max((*reverse_surge(v, ohm), name) for name, v, ohm in P.REVERSE_SURGES)
    if reverse[0] >= ss["reverse_v"] or reverse[1] > tvs["ipp_a"]:
        raise P.PartsError(f"hardware/parts.py: the TVS {tvs['mpn']} holds {reverse[2]} at "
                           f"-{reverse[0]:.1f} V and {reverse[1]:.1f} A, not above the surge "
                           f"stopper's -{ss['reverse_v']:g} V within its {tvs['ipp_a']:g} A; "
                           "choose a TVS with a lower breakdown")
    sense_ohm = ss["sense_v"] / (P.choices(b)["input_fuse_a"] * P.CURRENT_LIMIT_MARGIN)
    return {**cl, "weakest": weakest, "front": front, "sense_ohm": sense_ohm,
            "sense": P.shunt_for(sense_ohm, ss["sense_v"] / sense_ohm), "reverse": reverse}


def divider(top: float, bottom: float, ref_v: float, ref_tol: float,
            res_tol: float) -> tuple[float, float, float]:
    """(nominal, lowest, highest) input voltage at which a ``top`` over ``bottom`` divider puts
    ``ref_v`` on its joint, with the reference's and both resistors' tolerances."""
    def at(ref: float, t: float) -> float:
        return ref * (1 + top * (1 + t) / (bottom * (1 - t)))
    return (at(ref_v, 0.0), at(ref_v * (1 - ref_tol), -res_tol),
            at(ref_v * (1 + ref_tol), res_tol))


def timeouts(tmr_f: float) -> tuple[float, float]:
    """(overcurrent, overvoltage) time-out of the surge stopper with ``tmr_f`` on its TMR pin:
    the data sheet's short-circuit example (P^2 t = (V_IN x dV_SNS / R_SNS)^2 x t_OC) solved for
    its t_OC and scaled by the capacitance; the timer charges 5 times slower in an
    overvoltage."""
    ss = P.INPUT["surge_stopper"]
    ex = ss["tmr_example"]
    t_oc = ex["p2t_w2s"] / (ex["v_in"] * ex["sense_v"] / ex["sense_ohm"]) ** 2
    t_oc *= tmr_f / ex["tmr_f"]
    return t_oc, t_oc * ss["tmr_oc_ov_ratio"]


def stopper(b: dict[str, Any], vmin: float, vmax: float, board_a: float,
            prot: dict[str, Any]) -> dict[str, Any]:
    """What the surge stopper's support parts (``parts.STOPPER``) set on revision ``b``, with
    input range ``vmin`` to ``vmax``: its time-outs, its UV and OV thresholds, the bulk
    capacitor's charge at the current limit and the pass MOSFET's P^2 t. ``PartsError`` if the
    UV threshold could reach the lowest input, the OV threshold the highest, the overcurrent
    time-out run out before the bulk capacitor is charged, or the P^2 t reach what the MOSFET's
    SOA allows (once ``parts.py`` has that figure)."""
    ss, sp, inp = P.INPUT["surge_stopper"], P.STOPPER, P.INPUT
    top, mid, bottom = (sp[k]["ohm"] for k in ("uv_top", "uv_mid", "uv_bottom"))
    th = (ss["uv_ov_v"], ss["uv_ov_tol"], P.UV_OV_RES_TOL)
    uv, ov = divider(top, mid + bottom, *th), divider(top + mid, bottom, *th)
    tmr = sp["timer"]
    t_oc, t_ov = timeouts(tmr["farad"])
    shortest = (1 - tmr["tol"]) * (1 - tmr["tempco"])
    short_a = ss["short_sense_v"] / prot["sense_ohm"]
    charge_s = inp["bulk"]["farad"] * vmax / short_a
    held_v = inp["tvs"]["vbr_max_v"] - prot["low"]
    p2t = {SHORTED: (vmax * short_a) ** 2 * t_oc * ss["p2t_margin"],
           SURGE: (board_a * held_v) ** 2 * t_ov * ss["p2t_margin"]}
    refs = "-".join((sp["uv_top"]["ref"], sp["uv_bottom"]["ref"]))
    if uv[2] >= vmin:
        raise P.PartsError(
            f"hardware/parts.py: {b['name']}'s surge stopper turns the board off below up to "
            f"{uv[2]:.2f} V (UV, string {refs}), not under its lowest input of {vmin:g} V; "
            "lower uv_top or raise uv_mid in STOPPER")
    if ov[1] <= vmax:
        raise P.PartsError(
            f"hardware/parts.py: {b['name']}'s surge stopper refuses to start from "
            f"{ov[1]:.2f} V (OV, string {refs}), not above its highest input of {vmax:g} V; "
            "lower uv_bottom in STOPPER")
    if t_oc * shortest <= charge_s * P.START_MARGIN:
        raise P.PartsError(
            f"hardware/parts.py: the surge stopper's overcurrent time-out ("
            f"{t_oc * shortest * 1000:.2f} ms at its shortest, {tmr['ref']} "
            f"{tmr['farad'] * 1e9:g} nF) is not {P.START_MARGIN:g} x the "
            f"{charge_s * 1000:.2f} ms its current limit takes to charge {b['name']}'s bulk "
            "capacitor: the board would not start; raise the timer's farad in STOPPER")
    soa = inp["mosfet"]["soa_p2t_w2s"]
    worst = max(p2t, key=lambda k: p2t[k])
    if soa is not None and p2t[worst] >= soa:
        raise P.PartsError(
            f"hardware/parts.py: {b['name']}'s pass MOSFET {inp['mosfet']['mpn']} takes "
            f"{p2t[worst]:.0f} W^2 s ({worst}), not under the {soa:g} W^2 s its SOA allows; "
            "lower the timer's farad in STOPPER or choose a stronger MOSFET")
    return {"uv": uv, "ov": ov, "t_oc": t_oc, "t_ov": t_ov, "shortest": shortest,
            "short_a": short_a, "charge_s": charge_s, "held_v": held_v, "p2t": p2t}


def reverse_surge(source_v: float, source_ohm: float) -> tuple[float, float]:
    """(volts, amperes) at which the TVS holds a surge of ``source_v`` from ``source_ohm``:
    above its breakdown (at its highest) the TVS is a resistance ``(clamp_v - vbr_max_v) /
    ipp_a``, so the current is what the source drives through both."""
    tvs = P.INPUT["tvs"]
    r_tvs = (tvs["clamp_v"] - tvs["vbr_max_v"]) / tvs["ipp_a"]
    amps = max(0.0, (source_v - tvs["vbr_max_v"]) / (source_ohm + r_tvs))
    return tvs["vbr_max_v"] + amps * r_tvs, amps


def limits(b: dict[str, Any]) -> dict[str, Any]:
    """Every current and voltage limit of a revision, with what sets it."""
    c = P.choices(b)
    sw = P.SWITCHES[c["switch"]]
    sense = P.chip(b)
    mcu = P.MCU[b["mcu"]]
    inp = P.INPUT
    smart = "is_adc_pin" in b["sense"]
    if smart:  # no shunt: the switch's IS reads as a fault from fault_ua on
        r_ohm = 0.0
        fullscale_a = b["sense"]["fault_ua"] / 1e6 * b["sense"]["k_ilis"]
    else:
        r_ohm = b["sense"]["shunt_uohm"] / 1e6
        fullscale_a = sense["fullscale_v"] / r_ohm
    cont = min((sw["i_max_a"], f"the switch {sw['mpn']}"),
               (fullscale_a, f"the {sense['mpn']}'s full scale" + ("" if smart else
                                                                   " over the shunt")),
               (P.CONNECTORS["output_header"]["rating_a"], "the output connector"))
    # a smart switch protects itself at its own limit; a monitor's reading saturates at its full
    # scale, so the instant trip (and, for the TPS1H100, the limit it is set to) stays under it
    limit_a = sw["limit_a"] if smart else min(sw["limit_a"], fullscale_a)
    trip_cap = min((limit_a, f"the {limit_a:g} A the switch limits to"),
                   (fullscale_a, f"the {fullscale_a:.2f} A the sense reads up to"))
    shunt_w, shunt_mpn, shunt_pkg = (0.0, "", "") if smart else P.shunt_for(
        r_ohm, max(cont[0], limit_a))
    adc_max_v = mcu["adc_vref_v"] * b["vin"]["divider"]
    prot = protection(b)
    vmax = min((int(prot["low"] * 10) / 10, f"the surge stopper's clamp (from "
                f"{prot['low']:.2f} V)"),
               (sw["v_op"][1], f"the switch {sw['mpn']}"),
               (sense["bus_max_v"], f"the {sense['mpn']}'s bus input"),
               (adc_max_v, "the ADC behind the divider"),
               (inp["regulator"]["v_in"][1], f"the regulator {inp['regulator']['mpn']}"))
    vmin = max((sw["v_op"][0], f"the switch {sw['mpn']}"),
               (inp["regulator"]["v_in"][0], f"the regulator {inp['regulator']['mpn']}"))
    if inp["tvs"]["standoff_v"] <= vmax[0]:  # the battery at its highest, or reversed
        raise P.PartsError(f"hardware/parts.py: the TVS {inp['tvs']['mpn']} stands off "
                           f"{inp['tvs']['standoff_v']:g} V, not above {b['name']}'s highest "
                           f"input of {vmax[0]:g} V; choose a TVS with a higher standoff")
    in_fuse = c["input_fuse_a"]
    board_a = in_fuse / P.FUSE_MARGIN
    support = stopper(b, vmin[0], vmax[0], board_a, prot)
    n_chips = 0 if smart else -(-b["channels"] // sense["per_chip"])
    top, bottom = P.PASSIVES["readback_series"]["ohm"], P.PASSIVES["readback_pulldown"]["ohm"]
    bus_pf = n_chips * P.I2C_PIN_PF + P.I2C_TRACE_PF
    return {
        "switch": sw, "sense": sense, "mcu": mcu, "module": P.module(b), "shunt_ohm": r_ohm,
        "fullscale_a": fullscale_a, "cont_a": cont[0], "cont_by": cont[1], "limit_a": limit_a,
        "fuse_a": P.fuse_for(cont[0]), "shunt": (shunt_w, shunt_mpn, shunt_pkg),
        "shunt_loss_w": limit_a * limit_a * r_ohm if limit_a > cont[0] else
        cont[0] * cont[0] * r_ohm,
        "instant_rated_a": trip_cap[0] / TRIP_FACTOR, "trip_cap_by": trip_cap[1],
        "adc_max_v": adc_max_v, "vmax": vmax[0], "vmax_by": vmax[1], "vmin": vmin[0],
        "vmin_by": vmin[1], "input_fuse_a": in_fuse, "board_a": board_a,
        "fet_loss_w": board_a * board_a * inp["mosfet"]["rds_on_ohm"], "protection": prot,
        "stopper": support,
        "n_chips": n_chips, "bus_pf": bus_pf, "readback": bottom / (top + bottom),
        "pullup_max_ohm": P.I2C_RISE_NS * 1e-9 / (0.8473 * bus_pf * 1e-12), "smart": smart,
    }


def sense_parts(b: dict[str, Any], lim: dict[str, Any]) -> list[list[Any]]:
    """The rows that sense the currents: the monitors, their shunts and the I2C pull-ups, or
    a smart-switch board's two legs of the IS sense resistor."""
    if lim["smart"]:
        return [[ref, 1, P.PASSIVES[key]["mfr"], P.PASSIVES[key]["mpn"], P.PASSIVES[key]["what"]]
                for ref, key in (("RIS1", "is_top"), ("RIS2", "is_adc"))]
    n, sense = b["channels"], lim["sense"]
    w, shunt_mpn, pkg = lim["shunt"]
    return [
        [f"SEN1-SEN{lim['n_chips']}", lim["n_chips"], sense["mfr"], sense["mpn"],
         sense["what"]],
        [f"RS1-RS{n}", n, "Vishay Dale", shunt_mpn,
         f"shunt {lim['shunt_ohm'] * 1000:g} mOhm 1 % {w:g} W ({pkg}): I^2 R at "
         f"{max(lim['cont_a'], lim['limit_a']):g} A is {lim['shunt_loss_w']:.2f} W, "
         f"x {P.SHUNT_MARGIN:g} margin"],
        ["RP1-RP2", 2, P.PASSIVES["i2c_pullup"]["mfr"], P.PASSIVES["i2c_pullup"]["mpn"],
         P.PASSIVES["i2c_pullup"]["what"]],
    ]


def protection_parts(lim: dict[str, Any]) -> list[list[Any]]:
    """The surge stopper's sense resistor and the FB divider that sets its clamp."""
    prot = lim["protection"]
    w, mpn, pkg = prot["sense"]
    limit_a = P.INPUT["surge_stopper"]["sense_v"] / prot["sense_ohm"]
    return [
        ["RLIM", 1, "Vishay Dale", mpn, f"current sense {prot['sense_ohm'] * 1000:g} mOhm 1 % "
         f"{w:g} W ({pkg}): the surge stopper limits at 50 mV, {limit_a:g} A "
         f"({P.CURRENT_LIMIT_MARGIN} x the input fuse)"],
        ["RFB1", 1, "Yageo", P.CLAMP_MPN.format(kohm=prot["top_kohm"]),
         f"{prot['top_kohm']} kOhm 0.1 % 0603: the surge stopper's FB divider, top (clamp "
         f"{prot['nominal']:.1f} V)"],
        ["RFB2", 1, P.PASSIVES["divider_bottom"]["mfr"], P.PASSIVES["divider_bottom"]["mpn"],
         f"{P.CLAMP_BOTTOM_OHM // 1000} kOhm 0.1 % 0603: the surge stopper's FB divider, "
         "bottom"],
    ]


def stopper_parts(lim: dict[str, Any]) -> list[list[Any]]:
    """The surge stopper's support parts (``parts.STOPPER``): its timer capacitor, its UV/OV
    string and its SHDN pull-up, the first two with what they set."""
    sup, sp = lim["stopper"], P.STOPPER
    sets = {"timer": f": time-outs {sup['t_oc'] * 1000:.2f} ms (overcurrent), "
                     f"{sup['t_ov'] * 1000:.1f} ms (overvoltage)",
            "uv_top": f"; with {sp['uv_mid']['ref']} and {sp['uv_bottom']['ref']}: the board "
                      f"off under {sup['uv'][0]:.1f} V (UV), no start above {sup['ov'][0]:.2f} V"
                      " (OV)"}
    return [[p["ref"], 1, p["mfr"], p["mpn"], p["what"] + sets.get(key, "")]
            for key, p in sp.items()]


def bom_rows(b: dict[str, Any]) -> list[list[str]]:
    """(reference, quantity, manufacturer, part number, description), one row per part."""
    lim = limits(b)
    n = b["channels"]
    sw = lim["switch"]
    n_sw = -(-n // sw["per_chip"])
    fuse_a, in_fuse = lim["fuse_a"], lim["input_fuse_a"]
    rows = [
        ["U1", 1, lim["module"]["mfr"], lim["module"]["mpn"], lim["module"]["what"]],
        ["U2", 1, P.INPUT["regulator"]["mfr"], P.INPUT["regulator"]["mpn"],
         P.INPUT["regulator"]["what"]],
        ["U3", 1, P.INPUT["surge_stopper"]["mfr"], P.INPUT["surge_stopper"]["mpn"],
         P.INPUT["surge_stopper"]["what"]],
        ["Q1-Q2", 2, P.INPUT["mosfet"]["mfr"], P.INPUT["mosfet"]["mpn"],
         P.INPUT["mosfet"]["what"]],
        *protection_parts(lim),
        *stopper_parts(lim),
        ["D1", 1, P.INPUT["tvs"]["mfr"], P.INPUT["tvs"]["mpn"], P.INPUT["tvs"]["what"]],
        ["F0", 1, "Littelfuse", P.FUSE_MPN.format(amps=in_fuse),
         f"ATO blade fuse {in_fuse} A 32 V: the input"],
        [f"F1-F{n}", n, "Littelfuse", P.FUSE_MPN.format(amps=fuse_a),
         f"ATO blade fuse {fuse_a} A 32 V: one per channel ({lim['cont_a']:g} A continuous "
         f"x {P.FUSE_MARGIN})"],
        [f"XF0-XF{n}", n + 1, P.FUSE_HOLDER["mfr"], P.FUSE_HOLDER["mpn"],
         P.FUSE_HOLDER["what"]],
        [f"SW1-SW{n_sw}", n_sw, sw["mfr"], sw["mpn"], sw["what"]],
        *sense_parts(b, lim),
        ["J0", 1, P.CONNECTORS["input"]["mfr"], P.CONNECTORS["input"]["mpn"],
         P.CONNECTORS["input"]["what"]],
        [f"J1-J{n}", n, P.CONNECTORS["output_header"]["mfr"],
         P.CONNECTORS["output_header"]["mpn"], P.CONNECTORS["output_header"]["what"]],
        [f"P1-P{n}", n, P.CONNECTORS["output_plug"]["mfr"], P.CONNECTORS["output_plug"]["mpn"],
         P.CONNECTORS["output_plug"]["what"]],
        ["C0", 1, P.INPUT["bulk"]["mfr"], P.INPUT["bulk"]["mpn"], P.INPUT["bulk"]["what"]],
        ["RD1", 1, P.PASSIVES["divider_top"]["mfr"], P.PASSIVES["divider_top"]["mpn"],
         P.PASSIVES["divider_top"]["what"]],
        ["RD2", 1, P.PASSIVES["divider_bottom"]["mfr"], P.PASSIVES["divider_bottom"]["mpn"],
         P.PASSIVES["divider_bottom"]["what"]],
    ]
    if b.get("status_pins"):
        for ref, key in (("RB", "readback_series"), ("RG", "readback_pulldown"),
                         ("DC", "readback_clamp")):
            rows.append([f"{ref}1-{ref}{n}", n, P.PASSIVES[key]["mfr"], P.PASSIVES[key]["mpn"],
                         P.PASSIVES[key]["what"]])
    bypass = n_sw + lim["n_chips"] + 1
    rows.append([f"CB1-CB{bypass}", bypass, P.PASSIVES["bypass"]["mfr"],
                 P.PASSIVES["bypass"]["mpn"], P.PASSIVES["bypass"]["what"]])
    return [[str(x) for x in row] for row in rows]


def csv_text(b: dict[str, Any]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["reference", "quantity", "manufacturer", "mpn", "description"])
    w.writerows(bom_rows(b))
    return buf.getvalue()


def sense_limits(b: dict[str, Any], lim: dict[str, Any]) -> list[str]:
    """The limit rows of the current sensing: its full scale first, then the read-back and I2C
    pull-up (a monitor board), or the IS sense node's resolution, voltage and power (a
    smart-switch board)."""
    sense, mcu = lim["sense"], lim["mcu"]
    if not lim["smart"]:
        rows = [f"| sense full scale per channel | {lim['fullscale_a']:.2f} A | "
                f"{sense['fullscale_v'] * 1000:g} mV / {lim['shunt_ohm'] * 1000:g} mOhm |"]
    else:
        s, sw = b["sense"], lim["switch"]
        vref, r_adc = s["vref_mv"] / 1000, s["r_adc_ohm"]
        hi = sw["i_is_fault_a"][1]
        per_count = vref / 2 ** mcu["adc_bits"] / r_adc * s["k_ilis"]
        rows = [
            f"| sense full scale per channel | {lim['fullscale_a']:.2f} A | IS from "
            f"{s['fault_ua'] / 1000:g} mA on reads as a fault; x k_ILIS {s['k_ilis']} |",
            f"| load current per ADC count | {per_count * 1000:.1f} mA, about "
            f"{vref / 2 ** mcu['adc_enob'] / r_adc * s['k_ilis'] * 1000:.0f} mA effective | "
            f"{vref:g} V / {mcu['adc_bits']} bit / {r_adc} Ohm x k_ILIS {s['k_ilis']} |",
            f"| smallest load measured | {s['accurate_ma']} mA | below it k_ILIS is known only "
            "to about +-34 %: low, not measured |",
            f"| ADC pin at the highest fault current | {hi * r_adc:.2f} V | I_IS(FAULT) "
            f"{hi * 1000:g} mA x {r_adc} Ohm, under the {vref:g} V reference |",
            f"| sense resistor power at that current | upper leg "
            f"{hi * hi * (s['r_is_ohm'] - r_adc) * 1000:.0f} mW (rated "
            f"{P.PASSIVES['is_top']['watts'] * 1000:g} mW), lower leg {hi * hi * r_adc * 1000:.0f}"
            f" mW (rated {P.PASSIVES['is_adc']['watts'] * 1000:g} mW) | ({hi * 1000:g} mA)^2 x "
            f"{s['r_is_ohm'] - r_adc} Ohm and x {r_adc} Ohm |",
            f"| switch on-resistance per channel | {sw['rds_on_ohm'] * 1000:g} mOhm, "
            f"{lim['cont_a'] ** 2 * sw['rds_on_ohm']:.2f} W at {lim['cont_a']:g} A | "
            f"{sw['mpn']}, typical at 25 degC |",
        ]
    if b.get("status_pins"):
        rows.append(
            f"| output read-back at the GPIO, lowest input | {lim['vmin'] * lim['readback']:.2f}"
            f" V | the {P.PASSIVES['readback_series']['ohm'] // 1000} k / "
            f"{P.PASSIVES['readback_pulldown']['ohm'] // 1000} k divider at {lim['vmin']:g} V; "
            f"the GPIO reads 1 from {mcu['io_vih_v']:g} V; clamped at 3.3 V above |")
    if not lim["smart"]:
        rows.append(
            f"| I2C pull-up, largest | {lim['pullup_max_ohm'] / 1000:.1f} kOhm | "
            f"{P.I2C_RISE_NS} ns rise / (0.8473 x {lim['bus_pf']} pF: {lim['n_chips']} chips "
            "and the bus) |")
    return rows


def protection_limits(lim: dict[str, Any]) -> list[str]:
    """The input protection's rows: what the parts behind it can see, and what it stands."""
    prot, ss, tvs = lim["protection"], P.INPUT["surge_stopper"], P.INPUT["tvs"]
    weakest, front = prot["weakest"], prot["front"]
    return [
        f"| surge stopper clamp | {prot['nominal']:.1f} V, {prot['low']:.2f} V to "
        f"{prot['high']:.2f} V | {ss['mpn']}: FB {ss['fb_v']:g} V +-{ss['fb_tol'] * 100:g} % x "
        f"(1 + {prot['top_kohm']} k / {P.CLAMP_BOTTOM_OHM // 1000} k, "
        f"+-{P.RESISTOR_TOL * 100:g} %); highest under {weakest[0]}'s {weakest[1]:g} V "
        "absolute maximum, the lowest of the parts behind it |",
        f"| surge stopper current limit | {ss['sense_v'] / prot['sense_ohm']:g} A | "
        f"{ss['sense_v'] * 1000:g} mV / {prot['sense_ohm'] * 1000:g} mOhm; then its timer "
        "turns the pass MOSFET off and retries |",
        f"| TVS clamp at its rated surge | {tvs['clamp_v']:g} V | {tvs['mpn']}, before the surge"
        f" stopper: under the {front[0]:g} V of {front[1]}; standoff {tvs['standoff_v']:g} V, "
        "above the input range and a reversed battery |",
        f"| negative surge at the input | -{prot['reverse'][0]:.1f} V at "
        f"{prot['reverse'][1]:.1f} A | {prot['reverse'][2]}, the worse of pulse 1's two"
        f" levels, held by the {tvs['mpn']} (breakdown up to {tvs['vbr_max_v']:g} V); above the"
        f" {ss['mpn']}'s -{ss['reverse_v']:g} V, the rest blocked by its ideal-diode MOSFET |",
    ]


def soa_verdict() -> str:
    """What the pass MOSFET's P^2 t rows say of its SOA: checked against the figure in
    ``parts.py``, or not checked."""
    fet = P.INPUT["mosfet"]
    if fet["soa_p2t_w2s"] is None:
        return f"the {fet['mpn']}'s SOA figure was not found: not checked"
    return f"under the {fet['soa_p2t_w2s']:g} W^2 s the {fet['mpn']}'s SOA allows"


def stopper_limits(lim: dict[str, Any]) -> list[str]:
    """The rows of what the surge stopper's support parts set: its time-outs (TMR), the start-up
    they must outlast, the cool-down, the UV and OV thresholds and the pass MOSFET's stress.
    Page numbers are the LTC4364 data sheet's (``parts.LTC4364_TIMING``)."""
    ss, sp, sup = P.INPUT["surge_stopper"], P.STOPPER, lim["stopper"]
    prot, ex, tmr = lim["protection"], ss["tmr_example"], sp["timer"]
    kohm = [sp[k]["ohm"] / 1000 for k in ("uv_top", "uv_mid", "uv_bottom")]
    string = " + ".join(f"{r:g} k" for r in kohm)
    uv, ov = sup["uv"], sup["ov"]
    return [
        f"| surge stopper overcurrent time-out | {sup['t_oc'] * 1000:.2f} ms, at least "
        f"{sup['t_oc'] * sup['shortest'] * 1000:.2f} ms | {tmr['ref']} {tmr['farad'] * 1e9:g} nF:"
        f" the data sheet's short-circuit example (p. 16: {ex['v_in']:g} V, "
        f"{ex['sense_v'] * 1000:g} mV / {ex['sense_ohm'] * 1000:g} mOhm, "
        f"{ex['tmr_f'] * 1e9:g} nF: {ex['p2t_w2s']:g} W^2 s) solved for t_OC = "
        f"{ex['p2t_w2s']:g} / ({ex['v_in']:g} V x {ex['sense_v'] / ex['sense_ohm']:.2f} A)^2, x "
        f"{tmr['ref']} / {ex['tmr_f'] * 1e9:g} nF; -{tmr['tol'] * 100:g} % and "
        f"-{tmr['tempco'] * 100:g} % (X7R over temperature) at its shortest; TMR pulls FLT low "
        f"at {ss['tmr_flt_v']:g} V and turns Q1 off at {ss['tmr_off_v']:g} V (p. 10). With "
        f"{ex['v_in']:g} V across Q1: how the timer current changes with it was not found, "
        "not confirmed against a datasheet |",
        f"| surge stopper overvoltage time-out at the clamp | {sup['t_ov'] * 1000:.1f} ms, at least"
        f" {sup['t_ov'] * sup['shortest'] * 1000:.1f} ms | {ss['tmr_oc_ov_ratio']} x the "
        "overcurrent time-out (the timer charges that much slower in an overvoltage, p. 10; at "
        f"the same {ex['v_in']:g} V across Q1, not confirmed at others): "
        "the board rides through a surge this long at the clamp; a load dump (ISO 7637-2 pulse"
        " 5, 40 ms to 400 ms) outlasts it: Q1 turns off, and comes back on after the cool-down "
        "once the input is under the OV threshold |",
        f"| start-up: the bulk capacitor at the current limit | {sup['charge_s'] * 1000:.2f} ms | "
        f"{P.INPUT['bulk']['farad'] * 1e6:g} uF to {lim['vmax']:g} V at "
        f"{ss['short_sense_v'] * 1000:g} mV / {prot['sense_ohm'] * 1000:g} mOhm = "
        f"{sup['short_a']:g} A (the limit while OUT is under 1.5 V, p. 10); x "
        f"{P.START_MARGIN:g} is under the shortest overcurrent time-out, so the board starts |",
        "| surge stopper cool-down before a retry | not found | the LTC4364-2 turns Q1 back on "
        "after a cool-down period (p. 12); its length is not in the data sheet pages at hand: "
        "not confirmed against a datasheet |",
        f"| input under-voltage turn-off | {uv[0]:.2f} V, {uv[1]:.2f} V to {uv[2]:.2f} V | UV "
        f"{ss['uv_ov_v']:g} V x ({string}) / ({kohm[1]:g} k + {kohm[2]:g} k), "
        f"+-{P.UV_OV_RES_TOL * 100:g} % resistors, +-{ss['uv_ov_tol'] * 100:g} % threshold (not "
        f"confirmed against a datasheet); under the lowest input, {lim['vmin']:g} V "
        f"({lim['vmin_by']}): it never cuts inside the input range; the firmware's uv_off acts "
        "above it |",
        f"| input over-voltage lock-out | {ov[0]:.2f} V, {ov[1]:.2f} V to {ov[2]:.2f} V | OV "
        f"{ss['uv_ov_v']:g} V x ({string}) / {kohm[2]:g} k; above the highest input, "
        f"{lim['vmax']:g} V: a higher input keeps Q1 off at power-up and stops a retry after a "
        "fault, but does not turn Q1 off (p. 12) |",
        f"| pass MOSFET stress, {SHORTED} | {sup['p2t'][SHORTED]:.0f} W^2 s | "
        f"({lim['vmax']:g} V x {sup['short_a']:g} A)^2 x {sup['t_oc'] * 1000:.2f} ms x "
        f"{ss['p2t_margin']:g} for tolerances (p. 16); {soa_verdict()} |",
        f"| pass MOSFET stress, {SURGE} | "
        f"{sup['p2t'][SURGE]:.0f} W^2 s | ({lim['board_a']:g} A x "
        f"({P.INPUT['tvs']['vbr_max_v']:g} V - {prot['low']:.2f} V))^2 x "
        f"{sup['t_ov'] * 1000:.1f} ms x {ss['p2t_margin']:g}: the board's full current while Q1 "
        f"holds the clamp until the overvoltage time-out; {soa_verdict()} |",
    ]


def markdown(b: dict[str, Any]) -> str:
    lim = limits(b)
    sw = lim["switch"]
    name = b["name"]
    out = [
        f"# {name}: parts and limits", "",
        "Generated by `hardware/bom.py` from `firmware/boards` and `hardware/parts.py`; do not "
        "edit. The parts to order are in `bom.csv`, the pins in `pins.md`.", "",
        "## Limits", "",
        "| limit | value | set by |", "|---|---|---|",
        f"| input voltage | {lim['vmin']:g} V to {lim['vmax']:g} V | {lim['vmin_by']}; "
        f"{lim['vmax_by']} |",
        f"| input voltage the ADC can read | 0 V to {lim['adc_max_v']:.1f} V | "
        f"{lim['mcu']['adc_vref_v']:g} V reference x the 1:{b['vin']['divider']} divider |",
        f"| input voltage resolution | {lim['adc_max_v'] / 2 ** lim['mcu']['adc_bits'] * 1000:.1f}"
        f" mV per count, about {lim['adc_max_v'] / 2 ** lim['mcu']['adc_enob'] * 1000:.0f} mV"
        f" effective | {lim['mcu']['adc_bits']}-bit ADC, {lim['mcu']['adc_enob']:g} effective"
        " bits |",
        f"| continuous current per channel | {lim['cont_a']:g} A | {lim['cont_by']} |",
        *sense_limits(b, lim)[:1],
        f"| switch current limit per channel | {lim['limit_a']:g} A | {sw['mpn']} |",
        f"| fuse per channel | {lim['fuse_a']} A | {lim['cont_a']:g} A x {P.FUSE_MARGIN} |",
        f"| largest rated_ma for which the instant trip can fire | "
        f"{lim['instant_rated_a'] * 1000:.0f} mA | trip at {TRIP_FACTOR:g} x rated must stay "
        f"under {lim['trip_cap_by']} |",
        f"| input fuse | {lim['input_fuse_a']} A | the board's wiring |",
        f"| continuous current, whole board | {lim['board_a']:g} A | input fuse / "
        f"{P.FUSE_MARGIN} |",
        f"| input MOSFETs' loss at that current | {lim['fet_loss_w']:.2f} W each | "
        f"I^2 x {P.INPUT['mosfet']['rds_on_ohm'] * 1000:g} mOhm (Q1 pass, Q2 ideal diode) |",
        *protection_limits(lim),
        *stopper_limits(lim),
        *sense_limits(b, lim)[1:],
        "", "## The protected channel", "",
        "The channel the configuration marks `protected` (`dxboard flash --config`) powers the"
        " computer that runs the dxboard host. The board never switches it off for an I2t"
        " overload, a misreading sensor, a silent host or a shed; only the instant trip and the"
        " input's under-voltage cut-off (`uv_off`) do, and the host only with the force flag"
        " (`protocol/PROTOCOL.md`). Wire the host's computer to it"
        " and nothing else: without that computer nothing diagnoses the robot or switches its"
        f" channels back on. Its device must draw at most {lim['cont_a']:g} A continuous. Its"
        f" {lim['fuse_a']} A fuse is its overload protection, and a short is "
        + ("switched off and latched at" if lim["smart"] else "held at")
        + f" {lim['limit_a']:g} A by the {sw['mpn']}"
        + ("" if lim["smart"] else " until the switch's own thermal shutdown") + " (the"
        f" instant trip fires only for rated_ma up to {lim['instant_rated_a'] * 1000:.0f} mA)."
        " A second device on that channel would be as unprotected, and its fault would take"
        " the computer down.",
        "", "## Microcontroller", "",
        f"{lim['module']['what']} ({lim['module']['mfr']} {lim['module']['mpn']})."
        + ("" if lim["module"] is lim["mcu"] else
           f" Not the {lim['mcu']['what']} ({lim['mcu']['mpn']}): on its RP2040 this revision's"
           " protection tick is under the design's 1 ms of each 10 ms at the cycles per"
           " instruction measured, but not surely for code that costs more cycles, where the"
           " RP2350 keeps it under (`hardware/README.md`). The firmware files are the same; the"
           " limits above are worked out from the RP2040's figures, the part the tests model.")
        + " An ESP32-S3 module is"
        " the better choice for a revision that senses current with the MCU's own ADC (20 ADC"
        " channels against the RP2040's 3 at about 8.7 effective bits) or needs more RAM or"
        " GPIOs; see `hardware/README.md`.",
        "", "## Parts", "",
        "| reference | qty | manufacturer | part number | what |", "|---|---|---|---|---|",
    ]
    out += ["| " + " | ".join(row) + " |" for row in bom_rows(b)]
    return "\n".join(out) + "\n"


def generate(out: Path) -> list[Path]:
    return write(out, (("bom.csv", csv_text), ("board.md", markdown)))


def main(argv: list[str]) -> int:
    try:
        paths = generate(Path(argv[0]) if argv else HERE)
    except (P.PartsError, KeyError) as exc:
        msg = str(exc) if isinstance(exc, P.PartsError) else (
            f"firmware/boards: a revision lacks the key {exc}; see firmware/boards/__init__.py")
        print(msg, file=sys.stderr)
        return 2
    for path in paths:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
