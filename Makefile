# Vehicle unit firmware: one entry point for building, running and testing.
#
#   make            build firmware library, simulator, tools and tests
#   make run        firmware on the simulated plant, console on this terminal
#   make check      build and run the whole test suite
#   make clean      remove build/
#   V=1             show full commands
#   CC=, CROSS_COMPILE=, BUILD=, SANITIZE=1 respected

BUILD ?= build
CROSS_COMPILE ?=
ifeq ($(origin CC),default)
CC := $(CROSS_COMPILE)gcc
endif
AR := $(CROSS_COMPILE)ar
PKG_CONFIG ?= pkg-config

ifeq ($(V),1)
Q :=
else
Q := @
endif

OPT ?= -O2
WARN := -Wall -Wextra -Werror -Wmissing-prototypes -Wstrict-prototypes
STRICT := -Wconversion -Wshadow -Wsign-conversion
CFLAGS_BASE := -std=c11 $(OPT) -g $(WARN) -I. -MMD -MP
HOST_DEFS := -D_GNU_SOURCE
LDLIBS_HOST := -lexpat -lm

ifeq ($(SANITIZE),1)
CFLAGS_BASE += -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
LDFLAGS += -fsanitize=address,undefined
endif
# Atomic counters: the link tests run the frame code on two threads, and
# racing increments left a branch of proto/frame.c counted negative
# (gcovr refuses the report).
ifeq ($(COVERAGE),1)
CFLAGS_BASE += --coverage -fprofile-update=atomic -O0
LDFLAGS += --coverage -fprofile-update=atomic
endif

# Per-area flags: firmware/ is freestanding and held to the strict warnings,
# proto/ too; host code may use libc and POSIX.
CFLAGS_firmware := $(CFLAGS_BASE) $(STRICT) -ffreestanding
CFLAGS_proto := $(CFLAGS_BASE) $(STRICT) $(HOST_DEFS)
CFLAGS_hal := $(CFLAGS_BASE) $(HOST_DEFS)
CFLAGS_host_sim := $(CFLAGS_BASE) $(HOST_DEFS)
CFLAGS_tools := $(CFLAGS_BASE) $(HOST_DEFS)
CFLAGS_tests := $(CFLAGS_BASE) $(HOST_DEFS) -Wno-missing-prototypes

FW_SRC := $(wildcard firmware/*.c)
# proto/: the unit's side and what it shares with hosts; proto/client/: the
# host's client library. hal/posix/: host support (configuration reader,
# SocketCAN, tty, clock, log) for the Linux main, the simulator and tools;
# hal/modbus/: Modbus drive profiles (plain C, shared with a board's master).
PROTO_SRC := $(wildcard proto/*.c proto/client/*.c)
HOST_SRC := $(wildcard hal/posix/*.c hal/modbus/*.c)
SIM_SRC := $(filter-out %_main.c,$(wildcard host_sim/*.c))
TEST_SRC := $(wildcard tests/test_*.c)
TEST_SUPPORT_SRC := $(filter-out tests/test_%,$(wildcard tests/*.c)) $(wildcard tests/model/*.c)

objs = $(patsubst %.c,$(BUILD)/obj/%.o,$(1))

FW_LIB := $(BUILD)/libfirmware.a
PROTO_LIB := $(BUILD)/libproto.a
HOST_LIB := $(BUILD)/libhost.a
SIM_LIB := $(BUILD)/libsim.a
TEST_SUPPORT_LIB := $(BUILD)/libtestsupport.a

# Link order: most dependent first.
HOST_LIBS := $(SIM_LIB) $(PROTO_LIB) $(HOST_LIB) $(FW_LIB)

PROGRAMS := $(BUILD)/vehicle-sim
TOOL_MAINS := $(wildcard tools/*_main.c)
PROGRAMS += $(patsubst tools/%_main.c,$(BUILD)/%,$(TOOL_MAINS))
TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))

.PHONY: all run check clean bench format
# Keep objects of test and tool programs (they are intermediate to pattern rules).
.SECONDARY:
all: $(FW_LIB) $(PROGRAMS) $(TESTS)

# Objects: the flags follow the top-level folder of the source.
$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $<")
	$(Q)$(CC) $(CFLAGS_$(firstword $(subst /, ,$<))) $(EXTRA_CFLAGS) -c $< -o $@

$(FW_LIB): $(call objs,$(FW_SRC))
$(PROTO_LIB): $(call objs,$(PROTO_SRC))
$(HOST_LIB): $(call objs,$(HOST_SRC))
$(SIM_LIB): $(call objs,$(SIM_SRC))
$(TEST_SUPPORT_LIB): $(call objs,$(TEST_SUPPORT_SRC))
$(BUILD)/%.a:
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  AR      $@")
	$(Q)rm -f $@ && $(AR) rcs $@ $^

$(BUILD)/vehicle-sim: $(call objs,host_sim/vehicle_sim_main.c) $(HOST_LIBS)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS_HOST)

$(BUILD)/%: $(BUILD)/obj/tools/%_main.o $(HOST_LIBS)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS_HOST)

$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(TEST_SUPPORT_LIB) $(HOST_LIBS)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ -lcmocka $(LDLIBS_HOST) -lutil

run: $(BUILD)/vehicle-sim
	$(BUILD)/vehicle-sim --config config/vehicle.xml --io config/io.xml --realtime

# Suites under QEMU: a Debian kernel (real SocketCAN, GPIO, uinput) and the
# Cortex-M images on emulated boards (mk/cortexm.mk builds them); QEMU=0
# leaves them out for a quick local run.
CHECK_SUITES := tests/run_python_tests.sh tests/run_python_pkg_tests.sh \
	$(if $(filter 0,$(QEMU)),,tests/run_qemu_tests.sh tests/qemu/run_fw.sh tests/mcu/run_mcu.sh)

# Test programs that start vehicle-fw and its peers run in the QEMU guest on
# an instruction-counted clock (tests/qemu/fw_process.sh), not on the host.
GUEST_TESTS := $(BUILD)/tests/test_linux_modbus

check: all
	$(Q)tests/run_tests.sh $(BUILD) $(filter-out $(GUEST_TESTS),$(TESTS)) -- $(CHECK_SUITES)

# Every tracked C file (make lint checks the same set).
format:
	git ls-files '*.c' '*.h' | xargs clang-format -i

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)

# Optional parts: fuzzing, coverage, static analysis, cross builds, benchmarks.
-include $(wildcard mk/*.mk)
