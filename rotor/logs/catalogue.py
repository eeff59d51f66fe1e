"""The catalogue of production trigger patterns, by name, each an edge list
(:class:`rotor.logs.patterns.TriggerPattern`) with its published source.

Angles are crankshaft degrees over the pattern's turn (360° for a crank wheel, 720° for
a cam wheel), counted from the angle the source counts from. The geometry of the named
production patterns is that of the rusEFI project's trigger decoders (rusEFI, "trigger
decoders", ``firmware/controllers/trigger/decoders/``: the file is named with each), the
open-source engine controller whose unit tests decode real captures of these wheels;
where rusEFI has no description, that of the Speeduino project's decoders (named as such).
The missing-tooth wheels (``60-2``, ``36-1``, …) are the generic ``N-M`` form, also
available by shorthand for any N and gaps (:func:`find_pattern`).

``rotor wheels`` lists the catalogue; ``rotor wheels NAME`` shows one pattern's edges.
"""

from __future__ import annotations

import re

import numpy as np

from ..errors import LogError
from .patterns import TriggerPattern, pattern_from_wheel

__all__ = [
    "CATALOGUE",
    "find_pattern",
    "pattern_ways",
    "rank_patterns",
    "best_pattern",
    "decode_channel",
    "AmbiguousPattern",
]

_MITSU = "rusEFI trigger decoders, trigger_mitsubishi.cpp"
_MAZDA = "rusEFI trigger decoders, trigger_mazda.cpp"
_CHRYSLER = "rusEFI trigger decoders, trigger_chrysler.cpp"
_NISSAN = "rusEFI trigger decoders, trigger_nissan.cpp"
_UNIVERSAL = "rusEFI trigger decoders, trigger_universal.cpp"
_MISC = "rusEFI trigger decoders, trigger_misc.cpp"
_HONDA = "rusEFI trigger decoders, trigger_honda.cpp"
_GM = "rusEFI trigger decoders, trigger_gm.cpp"
_SUBARU = "rusEFI trigger decoders, trigger_subaru.cpp"
_FORD = "rusEFI trigger decoders, trigger_ford.cpp"
_TOYOTA = "rusEFI trigger decoders, trigger_toyota.cpp"
_SPEEDUINO = "Speeduino (Josh Stewart et al.) trigger decoders, decoders.cpp"


_PHASER_RISING = tuple(22.5 * k for k in (0, 4, 8, 9, 12, 13, 14, 16, 17, 20, 21, 24, 28, 29, 30))


def _cam(x: float) -> float:
    """Cam degrees as crankshaft degrees."""
    return 2.0 * x


_GM24X_NARROW = "011111011100110001010000"
"""GM 24x: of the 24 teeth, from the one that starts at angle 0, which rise soon after the
falling edge before them (1) and which late (0) (rusEFI's 0x0A33BE, least significant bit first)."""


def _gm24(short: float) -> list[float]:
    """GM 24x: each tooth's rising edge after the falling edge before it [deg]."""
    return [short if b == "1" else 15.0 - short for b in _GM24X_NARROW]


_VQ30_ENDS: tuple[float, ...] = (52.0, 61.0, 70.0, 115.0, 124.0, 133.0, 142.0, 151.0, 160.0, 176.0, 233.0)
_VQ30_ENDS += (242.0, 251.0, 260.0, 291.0, 300.0, 309.0, 318.0, 327.0, 351.0, 360.0)
"""Nissan VQ30 cam: where its 21 teeth end [cam deg]."""


def _nm(name: str, title: str, teeth: int, gaps: tuple, layout: tuple | None, source: str, aliases=()):
    p = pattern_from_wheel(teeth, gaps, layout)
    return TriggerPattern(name, title, 360.0, p.rising_deg, p.falling_deg, "rising", "crank", source, tuple(aliases))


_PATTERNS = (
    _nm("60-2", "60-2 missing-tooth crank wheel (Bosch; GM 58x read by its teeth)", 60, (2,), None, _UNIVERSAL),
    _nm("36-1", "36-1 missing-tooth crank wheel (Ford EDIS)", 36, (1,), None, _UNIVERSAL),
    _nm("36-2", "36-2 missing-tooth crank wheel (Toyota, Mazda)", 36, (2,), None, _UNIVERSAL),
    _nm("24-1", "24-1 missing-tooth crank wheel", 24, (1,), None, _UNIVERSAL),
    _nm("12-1", "12-1 missing-tooth crank wheel", 12, (1,), None, _UNIVERSAL),
    _nm("8-1", "8-1 missing-tooth crank wheel (Kawasaki motorcycles)", 8, (1,), None, _UNIVERSAL),
    _nm("4-1", "4-1 missing-tooth crank wheel", 4, (1,), None, _UNIVERSAL),
    _nm(
        "36-2-1",
        "Mitsubishi 4B11 crank: 36 positions, 17 teeth, 2 missing, 16 teeth, 1 missing",
        36,
        (1, 2),
        (17, 16),
        _MITSU,
        ("TT_36_2_1",),
    ),
    _nm(
        "36-2-1-1",
        "Mitsubishi 6G75 crank: 36 positions, 11 teeth, 1 missing, 11 teeth, 1 missing, 10 teeth, 2 missing",
        36,
        (2, 1, 1),
        (11, 11, 10),
        _MITSU,
        ("TT_36_2_1_1",),
    ),
    _nm(
        "36-2-2",
        "Dodge Neon 2003, Nissan QR25 and MR18 crank: 36 positions, two gaps of 2 missing teeth 180° apart",
        36,
        (2, 2),
        (16, 16),
        _CHRYSLER + "; " + _NISSAN + " (initializeNissanQR25crank, initializeNissanMR18crank)",
        ("TT_DODGE_NEON_2003_CRANK", "TT_NISSAN_QR25", "TT_NISSAN_MR18_CRANK"),
    ),
    TriggerPattern(
        "arctic-cat",
        "Arctic Cat two-stroke crank: 24 positions, 11 teeth, 1 missing, 10 teeth, 2 missing",
        360.0,
        tuple([x - 7.5 for x in range(45, 196, 15)] + [x - 7.5 for x in range(225, 361, 15)]),
        tuple(list(range(45, 196, 15)) + list(range(225, 361, 15))),
        "falling",
        "crank",
        _MISC,
        ("TT_ARCTIC_CAT", "24-1-2"),
    ),
    TriggerPattern(
        "mazda-nb-crank",
        "Mazda Miata NB crank: two 4° teeth each half turn, rising edges 70° and 110° apart",
        360.0,
        (110.0, 180.0, 290.0, 0.0),
        (114.0, 184.0, 294.0, 4.0),
        "rising",
        "crank",
        _MAZDA,
        ("TT_MIATA_VVT",),
    ),
    TriggerPattern(
        "mazda-nb-cam",
        "Mazda Miata NB cam: three rising edges a cycle, 319°, 41° and 360° apart",
        720.0,
        (0.0, 360.0, 679.0),
        (),
        "rising",
        "cam",
        _MAZDA,
        ("VVT_MIATA_NB",),
    ),
    TriggerPattern(
        "mazda-na-cas-1",
        "Mazda Miata NA cam-angle sensor, first signal: windows of 72° and 143° a cycle",
        720.0,
        (216.9, 577.0),
        (288.8, 0.0),
        "both",
        "cam",
        _MAZDA,
        ("TT_MAZDA_MIATA_NA",),
    ),
    TriggerPattern(
        "mazda-na-cas-2",
        "Mazda Miata NA cam-angle sensor, second signal: four windows of about 70° a cycle",
        720.0,
        (53.0, 232.6, 412.4, 592.9),
        (122.6, 302.6, 482.8, 662.9),
        "both",
        "cam",
        _MAZDA,
    ),
    TriggerPattern(
        "mitsubishi-6g72-cam",
        "Mitsubishi 6G72 cam: four lows of 30, 65, 55 and 67.5 cam° a cam turn",
        720.0,
        tuple(_cam(x) for x in (82.5, 177.5, 262.5, 0.0)),
        tuple(_cam(x) for x in (52.5, 112.5, 207.5, 292.5)),
        "both",
        "cam",
        _MITSU,
        ("TT_VVT_MITSU_6G72",),
    ),
    TriggerPattern(
        "mitsubishi-4g63-crank",
        "Mitsubishi 4G63 crank: two teeth 180° apart, no gap",
        360.0,
        (0.0, 180.0),
        (80.0, 260.0),
        "rising",
        "crank",
        _MITSU,
    ),
    TriggerPattern(
        "mitsubishi-4g63-cam",
        "Mitsubishi 4G63 cam: a wide and a narrow tooth (135–225 and 315–360 cam°)",
        720.0,
        (_cam(135.0), _cam(315.0)),
        (_cam(225.0), 0.0),
        "both",
        "cam",
        _MITSU,
        ("VVT_MITSUBISHI_4G63",),
    ),
    TriggerPattern(
        "12-tooth",
        "12 evenly spaced crank teeth (Nissan cam-angle disc of 24 slots at cam speed)",
        360.0,
        tuple(30.0 * k for k in range(12)),
        tuple(30.0 * k + 15.0 for k in range(12)),
        "rising",
        "crank",
        _UNIVERSAL,
        ("TT_12_TOOTH_CRANK",),
    ),
    TriggerPattern(
        "single-tooth-cam",
        "one cam tooth a cycle (phase)",
        720.0,
        (0.0,),
        (20.0,),
        "rising",
        "cam",
        _UNIVERSAL,
        ("VVT_SINGLE_TOOTH",),
    ),
    TriggerPattern(
        "dodge-neon-2003-cam",
        "Dodge Neon 2003 cam: seven windows rising at 144, 216, 288, 360, 540, 612 and 684°",
        720.0,
        (144.0, 216.0, 288.0, 360.0, 540.0, 612.0, 684.0),
        (180.0, 252.0, 324.0, 504.0, 576.0, 648.0, 0.0),
        "rising",
        "cam",
        _CHRYSLER,
        ("TT_DODGE_NEON_2003_CAM",),
    ),
    TriggerPattern(
        "bosch-quick-start-cam",
        "Bosch quick-start cam: two wide and two narrow teeth (70, 20, 20, 70 cam°)",
        720.0,
        tuple(_cam(x) for x in (20.0, 110.0, 200.0, 290.0)),
        tuple(_cam(x) for x in (90.0, 130.0, 220.0, 0.0)),
        "falling",
        "cam",
        _UNIVERSAL,
        ("TT_VVT_BOSCH_QUICK_START",),
    ),
    TriggerPattern(
        "chrysler-phaser-cam",
        "Chrysler phaser cam (5.7/6.2/6.4 l OHV V8): 15 narrow teeth on a grid of 32 places (22.5°)",
        720.0,
        _PHASER_RISING,
        tuple(x + 10.0 for x in _PHASER_RISING),
        "rising",
        "cam",
        "inferred from a production capture (rusEFI's test capture of TT_CHRYSLER_PHASER, cam part 53022243AF): "
        "its rising edges sit on a grid of 22.5° within 4°; rusEFI's decoder, configureChryslerVtt15 in "
        "trigger_chrysler.cpp, not consulted",
        ("TT_CHRYSLER_PHASER", "chrysler-phaser", "chrysler-vtt15"),
    ),
    TriggerPattern(
        "nissan-hr-cam-in",
        "Nissan HR intake cam: four 10 cam° teeth ending at 120, 142, 240 and 360 cam°",
        720.0,
        tuple(_cam(x) for x in (110.0, 132.0, 230.0, 350.0)),
        tuple(_cam(x) for x in (120.0, 142.0, 240.0, 0.0)),
        "rising",
        "cam",
        _NISSAN,
        ("TT_NISSAN_HR_CAM_IN",),
    ),
    TriggerPattern(
        "honda-k-crank",
        "Honda K crank: 12 teeth 30° apart and a 13th tooth 10° after one of them (12+1)",
        360.0,
        (6.0,) + tuple(30.0 * k - 4.0 for k in range(1, 13)),
        (10.0,) + tuple(30.0 * k for k in range(1, 13)),
        "rising",
        "crank",
        _HONDA + " (configureHondaK_12_1)",
        ("TT_HONDA_K_CRANK_12_1", "TT_HONDA_K_12_1"),
    ),
    TriggerPattern(
        "honda-k-cam",
        "Honda K exhaust cam: four 15 cam° teeth ending at 70.5 cam° and 90 cam° apart, a 7 cam° one ending at 360 (4+1)",
        720.0,
        tuple(_cam(55.5 + 90.0 * k) for k in range(4)) + (_cam(353.0),),
        tuple(_cam(70.5 + 90.0 * k) for k in range(4)) + (0.0,),
        "rising",
        "cam",
        _HONDA + " (configureHondaK_4_1)",
        ("TT_HONDA_K_CAM_4_1", "TT_HONDA_K_4_1"),
    ),
    TriggerPattern(
        "gm-24x",
        "GM 24x crank (LS): falling edges 15° apart, each tooth 5° or 10° wide in a fixed sequence",
        360.0,
        # each rising edge 5° or 10° after the falling edge before it, in the sequence of _GM24X_NARROW
        tuple(15.0 * i + w for i, w in enumerate(_gm24(5.0))),
        tuple(15.0 * i for i in range(24)),
        "both",
        "crank",
        _GM + " (initGmLS24, initGmLS24_5deg)",
        ("TT_GM_24x", "TT_GM_24x_5"),
    ),
    TriggerPattern(
        "gm-24x-3",
        "GM 24x crank, 3° variant: falling edges 15° apart, each tooth 3° or 12° wide in a fixed sequence",
        360.0,
        tuple(15.0 * i + w for i, w in enumerate(_gm24(3.0))),
        tuple(15.0 * i for i in range(24)),
        "both",
        "crank",
        _GM + " (initGmLS24, initGmLS24_3deg); Speeduino wiki, GM 24X (12 wide and 12 narrow teeth, 12° and 3°)",
        ("TT_GM_24x_3", "TT_GM_24x_2"),
    ),
    TriggerPattern(
        "gm-7x",
        "GM 7x crank: six 5° teeth 60° apart and a seventh 10° before the sixth",
        360.0,
        (55.0, 115.0, 175.0, 235.0, 295.0, 345.0, 355.0),
        (60.0, 120.0, 180.0, 240.0, 300.0, 350.0, 0.0),
        "rising",
        "crank",
        _GM + " (configureGmTriggerWaveform)",
        ("TT_GM_7X",),
    ),
    TriggerPattern(
        "gm-60-2-2-2",
        "GM/Daewoo F8CV distributor: 60 positions a cam turn, three gaps of 2 missing 120 cam° apart",
        720.0,
        tuple(_cam(1.0 + 6.0 * j) for j in range(60) if j not in (12, 13, 32, 33, 52, 53)),
        tuple(_cam(4.0 + 6.0 * j) for j in range(60) if j not in (12, 13, 32, 33, 52, 53)),
        "rising",
        "cam",
        _GM + " (configureGm60_2_2_2)",
        ("TT_GM_60_2_2_2",),
    ),
    TriggerPattern(
        "36-2-2-2",
        "Subaru H4 crank (36-2-2-2): 36 positions, 13 teeth, 2 missing, 16 teeth, 2 missing, 1 tooth, 2 missing",
        360.0,
        tuple(10.0 * k for k in range(13)) + tuple(10.0 * k for k in range(15, 31)) + (330.0,),
        tuple(10.0 * k + 5.0 for k in range(12))
        + (135.0,)
        + tuple(10.0 * k + 5.0 for k in range(15, 30))
        + (315.0, 345.0),
        "rising",
        "crank",
        _SUBARU + " (initialize36_2_2_2); Speeduino, decoders.cpp (triggerSetup_ThirtySixMinus222: H4 13-16-1)",
        ("TT_36_2_2_2", "subaru-36-2-2-2"),
    ),
    TriggerPattern(
        "subaru-h6-36-2-2-2",
        "Subaru H6 crank (36-2-2-2): 36 positions, 19 teeth, 2 missing, 10 teeth, 2 missing, 1 tooth, 2 missing",
        360.0,
        tuple(10.0 * k for k in range(19)) + tuple(10.0 * k for k in range(21, 31)) + (330.0,),
        (),
        "rising",
        "crank",
        _SPEEDUINO + " (triggerSetup_ThirtySixMinus222: H6 19-missing-10-missing-1-missing)",
    ),
    TriggerPattern(
        "nissan-vq35-crank",
        "Nissan VQ35 crank: 36 positions, three gaps of 2 missing teeth 120° apart (10 teeth between)",
        360.0,
        tuple(25.0 + 10.0 * k + 120.0 * m for m in range(3) for k in range(10)),
        tuple(30.0 + 10.0 * k + 120.0 * m for m in range(3) for k in range(10)),
        "rising",
        "crank",
        _NISSAN + " (initializeNissanVQ35crank)",
        ("TT_NISSAN_VQ35",),
    ),
    TriggerPattern(
        "nissan-hr-crank",
        "Nissan HR crank: 36 positions, 10 teeth, 2 missing, 22 teeth, 2 missing",
        360.0,
        tuple(10.0 * k for k in range(10)) + tuple(10.0 * k for k in range(12, 34)),
        tuple(10.0 * k + 5.0 for k in range(9)) + (105.0,) + tuple(10.0 * k + 5.0 for k in range(12, 33)) + (355.0,),
        "rising",
        "crank",
        _NISSAN + " (initializeNissanHRcrank)",
        ("TT_NISSAN_HR",),
    ),
    TriggerPattern(
        "nissan-vq-cam",
        "Nissan VQ35 intake cam (VVT): six 10 cam° teeth ending at 120, 180, 200, 240, 260 and 360 cam°",
        720.0,
        tuple(_cam(x - 10.0) for x in (120.0, 180.0, 200.0, 240.0, 260.0, 360.0)),
        tuple(_cam(x) for x in (120.0, 180.0, 200.0, 240.0, 260.0, 0.0)),
        "rising",
        "cam",
        _NISSAN + " (initializeNissanVQvvt)",
        ("TT_VVT_NISSAN_VQ35",),
    ),
    TriggerPattern(
        "nissan-mr-cam",
        "Nissan MR18 cam (VVT): groups of 1, 3, 4 and 2 teeth 90 cam° apart, 17 cam° between teeth",
        720.0,
        tuple(_cam(x - 4.0) for x in (73.0, 163.0, 180.0, 197.0, 253.0, 270.0, 287.0, 304.0, 343.0, 360.0)),
        tuple(_cam(x) for x in (73.0, 163.0, 180.0, 197.0, 253.0, 270.0, 287.0, 304.0, 343.0, 0.0)),
        "rising",
        "cam",
        _NISSAN + " (initializeNissanMRvvt)",
        ("TT_NISSAN_MR18_CAM_VVT",),
    ),
    TriggerPattern(
        "nissan-vq30-cam",
        "Nissan VQ30 cam: 21 teeth of 4 cam° in groups of 3, 6, 1, 4, 5 and 2, 9 cam° apart within a group",
        720.0,
        tuple(_cam(x - 4.0) for x in _VQ30_ENDS),
        tuple(_cam(x) for x in _VQ30_ENDS),
        "rising",
        "cam",
        _NISSAN + " (initializeNissanVQ30cam)",
        ("TT_NISSAN_VQ30",),
    ),
    TriggerPattern(
        "nissan-sr20ve-cam",
        "Nissan SR20VE cam-angle sensor, cylinder windows: four windows 180° apart, one 16° wide, three 4°",
        720.0,
        (164.0, 356.0, 536.0, 716.0),
        (180.0, 360.0, 540.0, 0.0),
        "both",
        "cam",
        _NISSAN + " (initializeNissanSR20VE_4)",
        ("TT_NISSAN_SR20VE",),
    ),
    TriggerPattern(
        "kawasaki-kx450f",
        "Kawasaki KX450F crank: 18 teeth 20° apart, 3° wide but the last 10.8° wide",
        360.0,
        tuple(17.0 + 20.0 * i for i in range(17)) + (349.2,),
        tuple(20.0 + 20.0 * i for i in range(17)) + (0.0,),
        "rising",
        "crank",
        _UNIVERSAL + " (configureKawaKX450F)",
        ("TT_KAWA_KX450F",),
    ),
    TriggerPattern(
        "ford-st170-cam",
        "Ford ST170 (Duratec) cam: 8 positions a cam turn, 3 missing (teeth at 90, 180, 360, 540 and 720°)",
        720.0,
        (80.0, 170.0, 350.0, 530.0, 710.0),
        (90.0, 180.0, 360.0, 540.0, 0.0),
        "rising",
        "cam",
        _MISC + " (configureFordST170)",
        ("TT_FORD_ST170",),
    ),
    TriggerPattern(
        "ford-tfi-pip",
        "Ford TFI signature PIP (V8 distributor): eight windows ending 90° apart, 45° wide but one 22.5°",
        720.0,
        (67.5,) + tuple(90.0 * i - 45.0 for i in range(2, 9)),
        tuple(90.0 * i for i in range(1, 9)),
        "rising",
        "cam",
        _MISC + " (configureFordPip)",
        ("TT_FORD_TFI_PIP",),
    ),
    TriggerPattern(
        "ford-coyote-cam",
        "Ford Coyote cam (VVT): seven 10 cam° teeth ending at 45, 90, 150, 180, 240, 270 and 360 cam°",
        720.0,
        tuple(_cam(x - 10.0) for x in (45.0, 90.0, 150.0, 180.0, 240.0, 270.0, 360.0)),
        tuple(_cam(x) for x in (45.0, 90.0, 150.0, 180.0, 240.0, 270.0, 0.0)),
        "rising",
        "cam",
        _FORD + " (configureFordCoyote)",
        ("TT_VVT_FORD_COYOTE",),
    ),
    TriggerPattern(
        "ford-barra-cam",
        "Ford Barra cam (VVT, 3+1): four 5 cam° teeth ending at 60, 120, 240 and 360 cam°",
        720.0,
        tuple(_cam(x - 5.0) for x in (60.0, 120.0, 240.0, 360.0)),
        tuple(_cam(x) for x in (60.0, 120.0, 240.0, 0.0)),
        "rising",
        "cam",
        _MISC + " (configureBarra3plus1cam)",
        ("TT_VVT_BARRA_3_PLUS_1",),
    ),
    TriggerPattern(
        "mitsubishi-4g69-cam",
        "Mitsubishi 4G69 cam: six 5 cam° teeth ending at 90, 160, 180, 250, 270 and 360 cam°",
        720.0,
        tuple(_cam(x - 5.0) for x in (90.0, 160.0, 180.0, 250.0, 270.0, 360.0)),
        tuple(_cam(x) for x in (90.0, 160.0, 180.0, 250.0, 270.0, 0.0)),
        "rising",
        "cam",
        _MITSU + " (initializeMitsubishi4G69Cam)",
        ("TT_VVT_MITSUBISHI_4G69",),
    ),
    TriggerPattern(
        "toyota-uz-cam",
        "Toyota UZ cam: three 5 cam° teeth ending at 135, 270 and 360 cam°",
        720.0,
        tuple(_cam(x - 5.0) for x in (135.0, 270.0, 360.0)),
        tuple(_cam(x) for x in (135.0, 270.0, 0.0)),
        "rising",
        "cam",
        _TOYOTA + " (initializeUzCam)",
        ("TT_TOYOTA_3_TOOTH_UZ",),
    ),
    TriggerPattern(
        "daihatsu-4cyl-cam",
        "Daihatsu four-cylinder cam: four 10° teeth 180° apart and a fifth 30° into the cycle (4+1)",
        720.0,
        (20.0, 170.0, 350.0, 530.0, 710.0),
        (30.0, 180.0, 360.0, 540.0, 0.0),
        "rising",
        "cam",
        _MISC + " (configureDaihatsu4cyl)",
        ("TT_DAIHATSU_4_CYL",),
    ),
)


CATALOGUE: dict[str, TriggerPattern] = {p.name: p for p in _PATTERNS}
"""The named patterns, by name."""


def find_pattern(name: str) -> TriggerPattern:
    """The pattern named ``name``: a catalogue name or alias (any case, ``_`` for ``-``),
    ``N-tooth`` (N evenly spaced crank teeth), or an ``N-g1-g2-…`` shorthand (gaps spread as evenly as they go; a catalogue entry of
    that shorthand first). A :class:`LogError` naming the closest names otherwise."""
    if not isinstance(name, str):
        raise TypeError(f"pattern = {name!r}: a catalogue name (a str)")
    key = name.strip().lower().replace("_", "-")
    for p in CATALOGUE.values():
        if key == p.name or key in (a.lower().replace("_", "-") for a in p.aliases):
            return p
    m = re.fullmatch(r"(\d+)-tooth", key)
    if m and 1 <= int(m.group(1)) <= 1000:
        n = int(m.group(1))
        return TriggerPattern(
            f"{n}-tooth", f"{n} evenly spaced crank teeth", 360.0, tuple(360.0 * k / n for k in range(n)), (), "rising"
        )
    m = re.fullmatch(r"(\d+)((?:-\d+)*)", key)
    if m:
        teeth = int(m.group(1))
        gaps = tuple(int(g) for g in re.findall(r"\d+", m.group(2)))
        if 3 <= teeth <= 1000 and sum(gaps) <= teeth - 2 * max(len(gaps), 1):
            return pattern_from_wheel(teeth, gaps)
    import difflib

    close = difflib.get_close_matches(key, list(CATALOGUE), n=3, cutoff=0.4)
    hint = f" (closest: {', '.join(close)})" if close else ""
    raise LogError(f"pattern {name!r}: not in the catalogue{hint}; `rotor wheels` lists the names", argument="wheel")


def edge_strip(pattern: TriggerPattern, width: int = 72) -> str:
    """A picture of ``pattern``'s turn in ``width`` characters, of the edges that carry its
    position: ``^`` where a rising edge falls, ``v`` a falling one, ``X`` both, ``.`` none
    (left: angle 0)."""
    cells = [" "] * width
    marks = {"rising": "^", "falling": "v"}
    shown = ("rising", "falling") if pattern.read == "both" else (pattern.read,)
    for polarity, mark in ((q, marks[q]) for q in shown):
        for a in pattern.angles_deg(polarity):
            k = min(int(a / pattern.period_deg * width), width - 1)
            cells[k] = "X" if cells[k] not in (" ", mark) else mark
    return "".join(c if c != " " else "." for c in cells)


def catalogue_markdown() -> str:
    """The reference page of the catalogue (``docs/reference/trigger-patterns.md``): every
    pattern with its edges and a picture of them."""
    out = [
        "# Trigger patterns",
        "",
        "<!-- generated by rotor.logs.catalogue.catalogue_markdown(); tests/logs/test_catalogue.py checks it -->",
        "",
        "Every pattern rotor knows by name (`rotor wheels` lists them, `rotor wheels NAME` shows one; in Python",
        "`rotor.logs.catalogue.find_pattern(NAME)`). Angles are crankshaft degrees over the pattern's turn:",
        "360° for a wheel on the crankshaft, 720° for one on the camshaft. Any `N-g1-g2…` missing-tooth wheel",
        "is also named by its shorthand. The geometry of the production patterns is that of the rusEFI",
        "project's trigger decoders (the source file and function are named with each), or where so named",
        "that of the Speeduino project's decoders.",
        "",
        "In the pictures each character is 1/72 of the turn, angle 0 at the left, and shows the edges that",
        "carry the position: `^` a rising edge, `v` a falling one, `X` both in one character.",
        "",
    ]
    for p in CATALOGUE.values():
        rep = p.repeats()
        out += [
            f"## `{p.name}`",
            "",
            f"{p.title}. {p.kind.capitalize()} wheel, turn {p.period_deg:g}°, {p.edges_per_turn} {p.read} edges a turn"
            + (
                f"; its spacing repeats {rep}× a turn, so timing alone gives its angle modulo {p.period_deg / rep:g}°"
                if rep > 1
                else ""
            )
            + ".",
            "",
            "```text",
            edge_strip(p),
            "```",
            "",
            "- rising edges [deg]: " + (", ".join(f"{x:g}" for x in p.rising_deg) or "not stated"),
            "- falling edges [deg]: " + (", ".join(f"{x:g}" for x in p.falling_deg) or "not stated"),
        ]
        if p.aliases:
            out.append("- also known as: " + ", ".join(f"`{a}`" for a in p.aliases))
        if p.source:
            out.append(f"- geometry: {p.source}")
        out.append("")
    return "\n".join(out)


class AmbiguousPattern(LogError):
    """Two patterns of different geometry explain a channel's edges about equally."""


AMBIGUOUS = 0.85
"""Two patterns of different geometry whose scores are within this ratio explain the edges
about equally: the choice is refused, naming both [-]."""
RIVAL_RMS = 3.0
"""A pattern whose placement leaves log-ratio residuals more than this many times the best's
(beyond the decoder's close fit) is no rival to it [-]."""
MIN_EVIDENCE = 0.004
"""The least evidence per edge (:attr:`rotor.logs.patterns.PatternFit.evidence`) that a
pattern's placement must show, times the share of the edges it keeps [-]."""
RANKING_ROWS = 40_000
"""Of a long record, the patterns are ranked on its first this many rows (about 20 000 edges
of each polarity) [-]; the pattern taken is then placed on all of it."""
GATE_RMS = 0.25
"""The largest RMS log-ratio of neighbouring speeds over a ranked pattern's kept edges [-]: a
pattern placed on edges whose spacing it does not share leaves larger ones (real captures of
a cranking engine read as their own patterns leave up to about 0.23)."""
PULSE_TRAIN = 0.1
"""A channel whose periods two apart differ by less than this in log (95 % of them) is a plain
pulse train [-]."""
MIN_TURNS = 3.0
"""The fewest turns of a pattern its kept edges must span to be ranked [-]: its marks (a gap,
a wide tooth) seen three times or more."""
MIN_KEPT = 0.6
PARTIAL_KEPT = 0.25
"""The share of a channel's edges a pattern must explain to question a wheel found from the gaps [-]."""
"""The least share of a channel's edges a ranked pattern must keep [-]."""
RPM_RANGE = (10.0, 30_000.0)
"""The crankshaft speeds a reading may imply [rev/min]; outside, the pattern is not this signal's."""


def pattern_ways(pattern: TriggerPattern) -> list[tuple[str, str, str, bool]]:
    """(label, channel edges to take, the pattern's polarity, inverted kinds) of each way a
    digital channel can carry ``pattern``: its edges of the pattern's polarity, or of the other
    (an inverted signal)."""
    if pattern.read == "both":
        return [("both", "both", "both", False), ("both, inverted", "both", "both", True)]
    other = "falling" if pattern.read == "rising" else "rising"
    return [(pattern.read, pattern.read, pattern.read, False), (f"{other} (inverted)", other, pattern.read, False)]


def _pulse_train(t, v, name: str) -> bool:
    """Whether a digital channel is a plain pulse train (one tooth, repeated): its periods
    between neighbouring edges of both kinds alternate between two values, so it carries one
    ratio, and no pattern of more distinct marks read on both edges can be told from it."""
    from .patterns import channel_edges

    times, _ = channel_edges(t, v, "both", name=name)
    if times.size < 8:
        return False
    d = np.log(np.diff(times))
    return float(np.percentile(np.abs(d[2:] - d[:-2]), 95)) < PULSE_TRAIN


def rank_patterns(t, v, patterns=None, *, name: str = "encoder_d", partial: bool = False):  # noqa: C901
    """Every catalogue pattern (or ``patterns``) tried on a digital channel (``t`` [s], ``v``
    levels): a list of (score, fit, label) of those that fit, best first. The score is the
    fit's evidence per edge times the share of edges kept, halved for a pattern of two
    alternating spacings (one ratio is all that marks it) (at least :data:`MIN_EVIDENCE`,
    keeping at least :data:`MIN_KEPT` of the edges); patterns that timing cannot tell apart
    (:attr:`rotor.logs.patterns.TriggerPattern.evenly_spaced`) are not ranked; a reading implying a speed outside
    :data:`RPM_RANGE` is not this signal's. ``partial``: also the patterns that explain a part
    of the edges (at least :data:`PARTIAL_KEPT` of them, over two turns), to question a wheel
    found by other means."""
    from .patterns import channel_edges, decode_edges

    edges = {}
    out = []
    t = np.asarray(t, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    if t.size > RANKING_ROWS:  # ranked on the start of a long record; the one taken is placed on all of it
        t, v = t[:RANKING_ROWS], v[:RANKING_ROWS]
    train = _pulse_train(t, v, name)
    for p in patterns if patterns is not None else CATALOGUE.values():
        if p.evenly_spaced or (train and p.read == "both" and p.edges_per_turn // p.repeats() > 2):
            continue
        for label, take, pol, inverted in pattern_ways(p):
            if take not in edges:
                edges[take] = channel_edges(t, v, take, name=name)
            times, kinds = edges[take]
            if inverted:
                kinds = 1 - kinds
            try:
                fit = decode_edges(times, p, pol, kinds=kinds if pol == "both" else None)
            except LogError:
                continue
            _, rpm = fit.rpm_per_turn()
            if rpm.size == 0 or not (RPM_RANGE[0] < float(np.median(rpm)) < RPM_RANGE[1]):
                continue
            # a pattern of two alternating spacings is told from any other such signal by one ratio
            # alone: the freedom it leaves halves its score
            distinct = p.edges_per_turn // fit.repeats
            score = fit.kept * fit.evidence * min(1.0, (distinct - 1) / 2)
            if fit.evidence > 0 and fit.kept >= PARTIAL_KEPT and fit.rms <= GATE_RMS and fit.turns >= 2:
                out.append((score, fit, label))
    out.sort(key=lambda x: -x[0])
    return out if partial else [r for r in out if _clearly(r)]


def catalogue_layout(wheel) -> bool:
    """Whether a missing-tooth wheel as placed (:class:`rotor.logs.wheel.Wheel`, its gaps'
    layout found from a log) has the layout of the catalogue pattern of its spec, read round
    from any tooth; True where the catalogue has no such pattern or the layout is not known."""
    p = CATALOGUE.get(wheel.spec)
    if p is None or wheel.layout is None:
        return True
    mine = pattern_from_wheel(wheel.teeth, wheel.gaps, wheel.layout).intervals_deg()
    theirs = p.intervals_deg()
    return mine.size == theirs.size and any(np.allclose(np.roll(mine, k), theirs) for k in range(mine.size))


def _clearly(ranked: tuple) -> bool:
    """Whether a ranked (score, fit, label) explains the channel clearly enough to be taken."""
    score, fit, _ = ranked
    return score >= MIN_EVIDENCE and fit.kept >= MIN_KEPT and fit.turns >= MIN_TURNS


def _rivals(best, other) -> bool:
    """Whether ``other`` (a fit) explains the edges about as closely as ``best``: its log-ratio
    RMS within :data:`RIVAL_RMS` times the best's, or both within the decoder's close fit (a
    pattern that leaves residuals several times the best's explains the edges worse, whatever
    the structure its score credits it with)."""
    from .patterns import FIT_RMS

    return other.rms <= max(RIVAL_RMS * best.rms, FIT_RMS)


def best_pattern(
    t,
    v,
    patterns=None,
    *,
    name: str = "encoder_d",
    source: str = "the log",
    whole: bool = True,
    ranked: list | None = None,
):
    """The catalogue pattern that explains a digital channel's edges best: (fit, the edges
    taken in words, evidence in words). Refused (:class:`LogError`) where none fits, naming
    the best tried, or where two of different geometry fit about equally (within
    :data:`AMBIGUOUS`), naming both and how to pin one (``wheel=NAME``). ``whole=False``: the
    fit of a long record is that of its start (:data:`RANKING_ROWS`), for a caller that places
    the pattern by other means. ``ranked``: the channel's :func:`rank_patterns` with
    ``partial=True``, where the caller has it (not ranked again)."""
    ranked = [
        r for r in (rank_patterns(t, v, patterns, name=name, partial=True) if ranked is None else ranked) if _clearly(r)
    ]
    if not ranked:
        raise LogError(
            f"{source}: no catalogue pattern explains the edges of {name!r} (`rotor wheels` lists them); "
            "give the wheel (wheel=N-M or a catalogue name)",
            argument="wheel",
        )
    best = ranked[0]
    rival = next((r for r in ranked[1:] if r[1].pattern.name != best[1].pattern.name and _rivals(best[1], r[1])), None)
    if rival is not None and rival[0] >= AMBIGUOUS * best[0]:
        raise AmbiguousPattern(
            f"{source}: {best[1].pattern.name} ({best[2]} edges, score {best[0]:.4f}) and "
            f"{rival[1].pattern.name} ({rival[2]} edges, score {rival[0]:.4f}) explain the edges about "
            "equally; give the wheel (wheel=NAME) to pin one",
            argument="wheel",
        )
    fit = best[1]
    if whole and np.size(t) > RANKING_ROWS:
        fit = decode_channel(t, v, fit.pattern, best[2], name=name)
    why = (
        f"{best[1].pattern.name} explains the edges best (score {best[0]:.4f}: {best[1].kept:.0%} of the edges "
        f"kept, log-ratio rms {best[1].rms:.3f})"
        + (f"; next {rival[1].pattern.name} {rival[0]:.4f}" if rival is not None else "")
    )
    return fit, best[2], why


def decode_channel(t, v, pattern: TriggerPattern, label: str, *, name: str = "encoder_d"):
    """``pattern`` placed on every edge of a digital channel (``t`` [s], ``v`` levels), read
    the way ``label`` (of :func:`pattern_ways`) says."""
    from .patterns import channel_edges, decode_edges

    take, pol, inverted = next((w[1], w[2], w[3]) for w in pattern_ways(pattern) if w[0] == label)
    times, kinds = channel_edges(t, v, take, name=name)
    kinds = 1 - kinds if inverted else kinds
    return decode_edges(times, pattern, pol, kinds=kinds if pol == "both" else None)
