# Performance benchmarks (included from the top Makefile).
#
#   make bench              every figure of docs/performance.md: tick cost
#                           (callgrind; and on the Cortex-M4 image in QEMU
#                           with -icount), accuracy against the double reference,
#                           console/frame parse rates, 1 kHz loop lateness (60 s),
#                           motion on the default plant (tools/bench/plantbench.c)
#   make bench BENCH_QUICK=1  the same with a 5 s lateness run
#
# Built with the normal host flags (OPT, default -O2) into $(BUILD)/bench/.

BENCH_DIR := $(BUILD)/bench
BENCH_SECS := $(if $(filter 1,$(BENCH_QUICK)),5,60)
BENCH_RIG := $(call objs,tools/bench/rig.c hal/cortexm/loop_hal.c)
BENCH_PROGS := $(addprefix $(BENCH_DIR)/,tickcost accuracy parserate looplat plantbench streamcost \
	drivecycle)

$(BENCH_DIR)/tickcost: $(call objs,tools/bench/tickcost.c tools/bench/scenario.c) $(BENCH_RIG) \
	$(FW_LIB)
$(BENCH_DIR)/streamcost: $(call objs,tools/bench/streamcost.c tools/bench/scenario.c) $(BENCH_RIG) \
	$(PROTO_LIB) $(FW_LIB)
$(BENCH_DIR)/looplat: $(call objs,tools/bench/looplat.c) $(BENCH_RIG) $(FW_LIB)
$(BENCH_DIR)/accuracy: $(call objs,tools/bench/accuracy.c tools/ref/ref_motion.c) $(BENCH_RIG) \
	$(FW_LIB)
$(BENCH_DIR)/parserate: $(call objs,tools/bench/parserate.c) $(BENCH_RIG) $(PROTO_LIB) $(HOST_LIB) \
	$(FW_LIB)
$(BENCH_DIR)/drivecycle: $(call objs,tools/bench/drivecycle.c hal/modbus/mbmaster.c \
	hal/modbus/mbprofile.c)
$(BENCH_DIR)/plantbench: $(call objs,tools/bench/plantbench.c tools/bench/plantmetrics.c) \
	$(HOST_LIBS)
$(BENCH_PROGS):
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS_HOST)

# The same scenarios on the Cortex-M4 image in QEMU (tools/bench/mcu_tickcost.sh).
.PHONY: bench-mcu-image
bench-mcu-image:
	$(Q)$(MAKE) --no-print-directory TARGET=cortex-m4 BUILD=$(BUILD) $(BUILD)/cortex-m4/bench.elf

bench: $(BENCH_PROGS) $(BUILD)/linkbench bench-mcu-image
	$(Q)CC="$(CC)" OPT="$(OPT)" tools/bench/bench.sh $(BENCH_DIR) $(BENCH_SECS)

# The motion figures' module is also the tests' (tests/test_plantmetrics.c,
# tests/test_fidelity.c).
$(BUILD)/tests/test_plantmetrics $(BUILD)/tests/test_fidelity: $(BUILD)/tests/%: \
	$(BUILD)/obj/tests/%.o $(call objs,tools/bench/plantmetrics.c) $(TEST_SUPPORT_LIB) $(HOST_LIBS)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ -lcmocka $(LDLIBS_HOST) -lutil
