"""The test side's protocol facts against the RTL's, and the rule that keeps them apart.

The RTL names its protocol numbers in ``rtl/bissmaster/protocol.py``; the test side has its own,
written separately from ``docs/protocol.md``: ``tb/protocol_facts.py`` (what the
encoder model, the cocotb driver, the reference model and the model tests use),
``tb/master_contract.py`` (the one port fact among them, from docs/ports.md) and the control
side's own table in ``tb/encoder_model/control.py``. Every RTL constant must agree with one of
those, or with a value written in this file from the spec. A disagreement is a bug on one side
or the other: the spec decides which.

This is the only test-side file that imports ``bissmaster.protocol``; the guard tests below fail
if another one does, or if a model-side module imports the RTL at all.
"""

import ast
import math
from pathlib import Path

import pytest

import master_contract
import protocol_facts
from bissmaster import protocol
from encoder_model import control

from testkit import REPO


def _constants(module):
    return {name: value for name, value in vars(module).items()
            if name.isupper() and not name.startswith("_")}


RTL = _constants(protocol)
FACTS = _constants(protocol_facts)

#: Port facts in tb/master_contract.py that the RTL keeps in protocol.py.
CONTRACT_NAMES = ("MA_HALF_PERIOD_MIN", "QUIET_TIME_S", "DELAY_TOLERANCE_DEFAULT",
                  "DELAY_SETTLE_FRAMES")

#: The control side's own table (tb/encoder_model/control.py), under its own names:
#: ``RTL name: control.py's value``.
CONTROL = {
    "CRC4_WIDTH": control.CRC4_WIDTH,
    "CRC4_POLY": control.CRC4_POLY,
    "CRC4_XOR_OUT": control.CRC4_XOR_OUT,
    "CONTROL_ID_BITS": control.ID_BITS,
    "CONTROL_ADDRESS_BITS": control.ADDRESS_BITS,
    "REGISTER_BITS": control.DATA_BITS,
    "BANK_BYTES": control.BANK_SIZE,
    "CDM_IDLE_FRAMES": control.IDLE_FRAMES,
    "REG_BANK_SELECT": control.BANK_SELECT,
    "REG_EDS_BANK": control.EDS_BANK,
    "REG_PROFILE_ID": control.PROFILE_ID,
    "BP3_PROFILE_ID": control.BP3_ID,
    "BP3_VERSION": control.BP3_VERSION,
    "BP3_DL_MIN": control.BP3_DL_MIN,
    "BP3_DL_MAX_SEPARATE_CRC": control.BP3_DL_MAX[0],
    "BP3_DL_MAX_SAFETY": control.BP3_DL_MAX[1],
}

#: RTL constants no test-side module needs, each written here from the spec (or docs/ports.md)
#: so that none of the RTL's numbers goes unchecked.
RTL_ONLY = {
    "MA_FREQ_MIN_HZ": 80e3,             # section 9: 80 kHz .. 10 MHz permitted
    "MA_FREQ_MAX_HZ": 10e6,             # sections 3 and 9
    "MA_HALF_PERIOD_MAX": 65535,        # docs/ports.md: cfg_ma_half_period is 16 bits
    "SAMPLING_MOMENT_MIN_S": 3.225e-6,  # sections 2 and 3
    "SAMPLING_MOMENT_MAX_S": 3.275e-6,
    "ACK_MAX_RESOLUTE_S": 16e-6,        # section 3: RESOLUTE, FORTiS
    "ACK_MAX_EVOLUTE_S": 20e-6,         # section 3: EVOLUTE
    "PROCESSING_TIME_MAX_S": 40e-6,     # section 9
    "LINE_DELAY_MAX_S": 40e-6,          # section 9
    "BREAK_TIME_S": 40e-6,              # section 9: MA high 40 us after power-on or an error
    "SLAVE_TIMEOUT_MAX_S": 40e-6,       # section 9: static slave timeout 12.5 .. 40 us
    "EDS_BANK_NONE": (0x00, 0xFF),      # section 10: EDS bank pointer 0x00 or 0xFF = no EDS
}


def _same(a, b):
    """Equal; floats to within rounding (1.0e-12 relative); tuples element by element."""
    if isinstance(a, tuple) or isinstance(b, tuple):
        return (isinstance(a, tuple) and isinstance(b, tuple) and len(a) == len(b)
                and all(map(_same, a, b)))
    if isinstance(a, float) or isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=0)
    return a == b


def test_every_fact_of_the_test_side_names_an_rtl_constant():
    """The comparison goes by name: a name the RTL does not have would be compared with nothing.
    (If the RTL renamed a constant, rename it here and in tb/protocol_facts.py too.)"""
    ours = set(FACTS) | set(CONTRACT_NAMES) | set(CONTROL) | set(RTL_ONLY)
    assert sorted(ours - set(RTL)) == []


def test_every_rtl_constant_is_checked():
    """A new constant in protocol.py needs a test-side value: in tb/protocol_facts.py if the
    test side uses it, otherwise in RTL_ONLY above (from the spec, with its section)."""
    ours = set(FACTS) | set(CONTRACT_NAMES) | set(CONTROL) | set(RTL_ONLY)
    assert sorted(set(RTL) - ours) == []


def test_rtl_only_means_no_other_test_side_value():
    """RTL_ONLY is for what no test-side module has (protocol_facts and control.py share the
    CRC-4 facts: test_the_two_test_side_tables_agree)."""
    assert set(RTL_ONLY) & (set(FACTS) | set(CONTRACT_NAMES) | set(CONTROL)) == set()
    assert set(CONTRACT_NAMES) & set(FACTS) == set()


@pytest.mark.parametrize("name", sorted(FACTS))
def test_protocol_facts_agree_with_the_rtl(name):
    assert _same(FACTS[name], RTL[name]), (name, FACTS[name], RTL[name])


@pytest.mark.parametrize("name", CONTRACT_NAMES)
def test_master_contract_agrees_with_the_rtl(name):
    assert getattr(master_contract, name) == RTL[name]


@pytest.mark.parametrize("name", sorted(CONTROL))
def test_control_model_agrees_with_the_rtl(name):
    assert CONTROL[name] == RTL[name], (name, CONTROL[name], RTL[name])


@pytest.mark.parametrize("name", sorted(RTL_ONLY))
def test_rtl_only_constants_are_the_spec_values(name):
    assert _same(RTL_ONLY[name], RTL[name]), (name, RTL_ONLY[name], RTL[name])


def test_the_two_test_side_tables_agree():
    """control.py keeps its own CRC-4 and BP3 numbers; they must match tb/protocol_facts.py."""
    assert (control.CRC4_WIDTH, control.CRC4_POLY, control.CRC4_INIT, control.CRC4_XOR_OUT) == (
        protocol_facts.CRC4_WIDTH, protocol_facts.CRC4_POLY, protocol_facts.CRC_INIT,
        protocol_facts.CRC4_XOR_OUT)
    assert control.BP3_FEEDBACK_BITS == protocol_facts.NE_NW_BITS


# -- The rule: the test side takes no protocol value from rtl/ --------------------------------

def _py_files(*roots):
    for root in roots:
        path = REPO / root
        files = [path] if path.is_file() else sorted(path.rglob("*.py"))
        for f in files:
            if not any(part.startswith((".", "__pycache__", "sim_build"))
                       for part in f.relative_to(REPO).parts):
                yield f


def _imported_modules(path):
    """Every module an ``import`` or ``from ... import`` of ``path`` names, with the imported
    names of a ``from`` import as submodules (``from bissmaster import protocol`` gives
    ``bissmaster`` and ``bissmaster.protocol``)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            names |= {f"{node.module}.{alias.name}" for alias in node.names}
    return names


def _rtl_imports(path):
    return {n for n in _imported_modules(path) if n.split(".")[0] == "bissmaster"}


#: Files whose RTL imports are the point: this test (it compares the two tables).
PROTOCOL_IMPORT_ALLOWED = {"tb/tests/model/test_protocol_facts.py"}

#: The model side: the encoder model, the test side's tables, and everything under sim/ (the
#: testbench, the reference model, the scenarios, the tools). None of it may import the RTL.
MODEL_SIDE = ("tb/encoder_model", "tb/master_contract.py", "tb/protocol_facts.py", "sim")
#: Exempt, with what it may import: the runner generates the Verilog under test; the
#: control-channel and BP3 demo scenarios run bissmaster.bp3; the UART top's scenarios run
#: bissmaster.host.link and the host tool bissmaster.host.cli.
MODEL_SIDE_EXEMPT = {"sim/shared/runner.py": {"bissmaster", "bissmaster.generate"},
                     # The host software under test, run against the simulated core as a user
                     # runs it against the hardware; expected values still come from the model.
                     "sim/scenarios/control_channel.py": {"bissmaster", "bissmaster.bp3"},
                     "sim/scenarios/demo_bp3.py": {"bissmaster", "bissmaster.bp3"},
                     # The UART top's bus is the host's Link (bissmaster.host.link) over a
                     # UART model, and the host tool (bissmaster.host.cli) runs on it; the
                     # scenarios' expected values come from the map's source and the model.
                     "sim/shared/uart.py": {"bissmaster.host", "bissmaster.host.link"},
                     "sim/scenarios/bus.py": {"bissmaster.host.link",
                                              "bissmaster.host.link.BridgeError",
                                              "bissmaster.host", "bissmaster.host.cli"}}
# Not on the model side: block tests (tb/tests/*/test_*.py, tb/testkit/) and the
# formal harnesses (tb/formal/) import the blocks they test. They take protocol *values* from
# tb/protocol_facts.py and tb/master_contract.py: the first guard covers them too.


def test_no_test_side_file_imports_the_rtl_protocol_table():
    offenders = {}
    for f in _py_files("tb", "sim"):
        rel = f.relative_to(REPO).as_posix()
        bad = {n for n in _rtl_imports(f) if n == "bissmaster.protocol" or n.endswith(".*")}
        if bad and rel not in PROTOCOL_IMPORT_ALLOWED:
            offenders[rel] = sorted(bad)
    assert offenders == {}, "take protocol values from tb/protocol_facts.py"


def test_model_side_imports_nothing_from_the_rtl():
    offenders = {}
    for f in _py_files(*MODEL_SIDE):
        rel = f.relative_to(REPO).as_posix()
        bad = _rtl_imports(f) - MODEL_SIDE_EXEMPT.get(rel, set())
        if bad:
            offenders[rel] = sorted(bad)
    assert offenders == {}


def test_model_side_exemptions_are_still_needed():
    for rel, allowed in MODEL_SIDE_EXEMPT.items():
        assert _rtl_imports(REPO / rel), f"{rel} no longer imports the RTL: drop its exemption"
        assert _rtl_imports(REPO / rel) <= allowed


def test_the_guards_see_an_rtl_import(tmp_path):
    """Non-vacuity: the import forms the guards look for are found."""
    for source in ("from bissmaster import protocol\n", "import bissmaster.protocol as p\n",
                   "from bissmaster.protocol import LC_MAX\n", "from bissmaster import *\n"):
        f = tmp_path / "m.py"
        f.write_text(source)
        found = _rtl_imports(f)
        assert "bissmaster.protocol" in found or "bissmaster.*" in found, source
    assert len(list(_py_files("tb/encoder_model"))) >= 5
    assert REPO / "sim/shared/reference.py" in set(_py_files("sim"))
