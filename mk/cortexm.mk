# Cortex-M builds (included from the top Makefile).
#
#   make TARGET=cortex-m4   firmware/ and the link parsers of proto/ with
#                           arm-none-eabi-gcc -Os: static libraries, a minimal
#                           image (hal/cortexm), flash and RAM against budget
#                           (over budget fails the build, see MCU_BUDGET_ENFORCED)
#   make TARGET=cortex-m0   the same for ARMv6-M
#                           both fail if any object of the image references a
#                           floating-point helper (firmware/real.h: the
#                           boundary's numbers are Q32 on a board)
#   ARM_PREFIX=             toolchain prefix (default arm-none-eabi-)
#
# `make check` also runs the self-test of that floating-point check, and
# (unless QEMU=0) builds both images, the M4 against its budget, and the M4
# tick benchmark, for tests/mcu/run_mcu.sh to run them in QEMU.

ARM_PREFIX ?= arm-none-eabi-
ARM_CC := $(ARM_PREFIX)gcc
ARM_AR := $(ARM_PREFIX)ar
ARM_NM := $(ARM_PREFIX)nm
ARM_SIZE := $(ARM_PREFIX)size

# The application's room on a 128 KiB part, the rest kept for a boot
# loader and the parameter pages.
MCU_FLASH_BUDGET := 65536
MCU_RAM_BUDGET := 16384
# Targets whose build fails over budget: both, now that no image carries
# soft double (the M0's was generic C, 6.6 KiB).
MCU_BUDGET_ENFORCED := cortex-m4 cortex-m0

# The base the image is built for, as its configuration is compiled in
# (board_main.c): diff, the reference base, or omni (mecanum). Only that
# base's code is linked (firmware/config.h, VS_KIN_ONLY).
MCU_KIN ?= diff
MCU_KIN_ONLY := $(if $(filter omni,$(MCU_KIN)),1,0)

MCU_CPU_cortex-m4 := -mcpu=cortex-m4 -mthumb -mfloat-abi=soft
MCU_CPU_cortex-m0 := -mcpu=cortex-m0 -mthumb -mfloat-abi=soft

# The console and binary-frame parsers; the host client and CAN mapping stay on the host.
MCU_PROTO_SRC := $(filter $(addprefix proto/,cmdtab.c dispatch.c console.c fmt.c numparse.c wire.c frame.c \
	frame_srv.c link.c port.c server.c console_config.c bbox_wire.c bbox_text.c \
	stream.c stream_read.c stream_srv.c),$(PROTO_SRC))
# The plant behind the HAL (hal/cortexm/plant.h): MCU_DRIVES=loop, the
# loopback drives (the board suite's reference, without drive states);
# modbus, wheel drives over RS-485 Modbus RTU on the second UART, with the
# hardware watchdog's drives-off (into $(TARGET)-mb/). Every image, these
# included, is held to the budget (docs/mcu.md).
MCU_DRIVES ?= loop
MCU_PLANT_SRC := $(if $(filter loop,$(MCU_DRIVES)),hal/cortexm/loop_hal.c hal/cortexm/plant_loop.c,\
	hal/cortexm/plant_modbus.c hal/modbus/mbmaster.c hal/modbus/mbprofile.c)
MCU_BOARD_SRC := $(addprefix hal/cortexm/,startup.c systick.c uart.c board_main.c \
	small_libc.c udivmod64.c flashstore.c wdog.c) $(MCU_PLANT_SRC)

.PHONY: cortexm nofloat-selftest

ifneq ($(filter cortex-m4 cortex-m0,$(TARGET)),)
.DEFAULT_GOAL := cortexm

MCU := $(BUILD)/$(TARGET)$(if $(filter omni,$(MCU_KIN)),-omni)$(if $(filter modbus,$(MCU_DRIVES)),-mb)
# A 16-deep motion queue (2 kB of RAM less than the host's 32). The
# boundary's numbers in Q32, not double (firmware/real.h): no floating point
# in the image; -Wfloat-conversion catches a double constant handed to it
# without VS_REAL(). The M4 carries every jerk-limited profile (docs/jerk.md,
# docs/mcu.md: how the room was made); the M0 leaves out those that start or
# end at speed (53 KiB with them) and runs their acceleration-limited forms.
MCU_DEFS := -DMOTION_QUEUE_LEN=16 -DVS_REAL_Q32 -Wfloat-conversion -DVS_KIN_ONLY=$(MCU_KIN_ONLY) \
	-DVS_NO_JOYSTICK -DVS_NO_INPUTS $(if $(filter loop,$(MCU_DRIVES)),-DVS_NO_DRIVE_STATES) \
	$(if $(filter cortex-m0,$(TARGET)),-DMOTION_NO_ONLINE_JERK)
# The board's io.xml table: the reference base's four entries and four
# more (32 on a host): 0.8 KiB less in the unit and on the stack.
MCU_DEFS += -DVS_MAX_IO=8
# The Modbus master reads the board's compiled-in drive profile as constants
# (hal/modbus/mbmaster.c): 472 bytes less on the M4 (68,808 -> 68,336).
MCU_DEFS += $(if $(filter modbus,$(MCU_DRIVES)),-DMBD_PROFILE=board_mb_profile)
# And calls its port's functions directly (MBM_PORT_DIRECT, hal/modbus/mbmaster.h): 60 bytes less.
MCU_DEFS += $(if $(filter modbus,$(MCU_DRIVES)),-DMBM_PORT_DIRECT)
# Link-time optimisation: inlining and dead-code removal across files saves
# a tenth of the flash (49.4 KiB -> 44.5 KiB when it was brought in). Fat
# objects keep their machine code too, which check_nofloat.sh reads.
MCU_LTO := -flto -ffat-lto-objects
# One link-time partition: two copied small inline helpers into both. No
# interprocedural constant propagation: its specialised copies of callees
# cost 0.7 KiB of flash (measured) and buy nothing the tick budget needs.
# The link's code generation puts each datum in its own section, as the
# objects' does: its address comes from a literal where a section anchor
# was one more add (0.1 KiB).
MCU_LTO_LINK := -flto-partition=one -fno-ipa-cp -fdata-sections
# Code generation for size where -Os still chooses for speed (measured on
# the Modbus image): no second scheduling pass (0.2 KiB), blocks in source
# order (0.15 KiB), no caller-saved spills (0.1 KiB); branches, not
# conditional execution or switch tables, none of the tree loop
# optimisations, no mod/ref analysis (0.1 KiB together). make bench's worst
# tick is no slower: 7,517 instructions before them, 7,330 with them.
# Link-time optimisation takes them from the objects, function by function.
MCU_SIZE := -fno-schedule-insns2 -fno-reorder-blocks -fno-caller-saves -fno-if-conversion \
	-fno-if-conversion2 -fno-tree-switch-conversion -fno-tree-loop-optimize -fno-ipa-modref
MCU_BASE := -std=c11 -Os -fno-ipa-cp $(MCU_SIZE) -g $(WARN) -I. -MMD -MP $(MCU_CPU_$(TARGET)) \
	-ffunction-sections -fdata-sections $(MCU_LTO) $(MCU_DEFS)
MCU_CFLAGS_firmware := $(MCU_BASE) $(STRICT) -ffreestanding
# The board is short of flash: it leaves out the help lines ($help NAME gives
# the signature), 1.8 KiB, the room the jerk-limited profiles take. $config
# changes the compiled-in configuration (board_main.c) and keeps it in the
# store's flash pages (flashstore.c). Calls, not tail jumps, in the console
# and frames: 48 bytes less on the Modbus image (hal/ so is 16 more); no
# tree tail merging there: 56 less again. The command table's rows packed
# (proto/cmdtab.h, VS_CMD_PACKED): 16 bytes a row, not 28, 244 bytes less on
# the mecanum Modbus image.
MCU_CFLAGS_proto := $(MCU_BASE) -fno-optimize-sibling-calls -fno-tree-tail-merge $(STRICT) $(HOST_DEFS) -DVS_NO_HELP_TEXT -DBBOX_UNIT_PAGE=2 -DVS_TABLE_CRC_CONST -DVS_CMD_PACKED
MCU_CFLAGS_hal := $(MCU_BASE) -ffreestanding
mcu_objs = $(patsubst %.c,$(MCU)/obj/%.o,$(1))
# The board's memcpy, memset and the like, and its 64-bit division, are
# plain objects: calls to them that code generation makes after link-time
# optimisation must find them.
MCU_NO_LTO := $(MCU)/obj/hal/cortexm/small_libc.o $(MCU)/obj/hal/cortexm/udivmod64.o
$(MCU_NO_LTO): MCU_OBJ_FLAGS := -fno-lto

# The flags are this file's: a change to them rebuilds the objects.
$(MCU)/obj/%.o: %.c mk/cortexm.mk
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $@")
	$(Q)$(ARM_CC) $(MCU_CFLAGS_$(firstword $(subst /, ,$<))) $(MCU_OBJ_FLAGS) $(EXTRA_CFLAGS) \
		-c $< -o $@

$(MCU)/libfirmware.a: $(call mcu_objs,$(FW_SRC))
$(MCU)/libproto.a: $(call mcu_objs,$(MCU_PROTO_SRC))
$(MCU)/libfirmware.a $(MCU)/libproto.a:
	@$(if $(Q),echo "  AR      $@")
	$(Q)rm -f $@ && $(ARM_AR) rcs $@ $^

# newlib-nano; proto/numparse.c converts numbers itself (no strtod, no %f).
$(MCU)/vehicle.elf: $(call mcu_objs,$(MCU_BOARD_SRC)) $(MCU)/libproto.a $(MCU)/libfirmware.a \
		hal/cortexm/$(TARGET).ld
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(ARM_CC) $(MCU_CPU_$(TARGET)) -Os -flto $(MCU_LTO_LINK) -nostartfiles --specs=nano.specs \
		-Wl,--gc-sections -Wl,-Map=$(MCU)/vehicle.map -T hal/cortexm/$(TARGET).ld \
		-o $@ $(filter %.o %.a,$^) -lm -lc -lnosys -lgcc

# The reset-in-the-save test image (tests/mcu): the board's code with the
# store's cut hook (flashstore.h, $storecut K), the same libraries.
MCU_CUT_SRC := hal/cortexm/board_main.c hal/cortexm/flashstore.c
$(MCU)/obj-cut/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $@")
	$(Q)$(ARM_CC) $(MCU_CFLAGS_hal) -DBOARD_STORE_CUT $(EXTRA_CFLAGS) -c $< -o $@
$(MCU)/vehicle-cut.elf: $(call mcu_objs,$(filter-out $(MCU_CUT_SRC),$(MCU_BOARD_SRC))) \
		$(patsubst %.c,$(MCU)/obj-cut/%.o,$(MCU_CUT_SRC)) $(MCU)/libproto.a $(MCU)/libfirmware.a \
		hal/cortexm/$(TARGET).ld
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(ARM_CC) $(MCU_CPU_$(TARGET)) -Os -flto $(MCU_LTO_LINK) -nostartfiles --specs=nano.specs \
		-Wl,--gc-sections -T hal/cortexm/$(TARGET).ld \
		-o $@ $(filter %.o %.a,$^) -lm -lc -lnosys -lgcc

# The drives' test image (tests/mcu/mcu_drives.py): the board with the
# test-only extras $hang and $fault (hal/cortexm/test_extras.c) and the bus
# timing of a bench whose peers run on a loaded host (hal/cortexm/
# plant_modbus.c): a peer process or the relay not scheduled for a few
# hundred ms while the emulated board runs on must not fail a request: 1 s
# a request, 200 ms between a reply's bytes, a 5 s drive timeout.
MCU_TEST_DEFS := -DBOARD_MB_TIMEOUT_US=1000000u -DBOARD_MB_BYTE_US=200000u \
	-DBOARD_MB_DRIVE_TIMEOUT_MS=5000u
MCU_TEST_SRC := hal/cortexm/plant_modbus.c hal/cortexm/test_extras.c
$(MCU)/obj-test/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CC      $@")
	$(Q)$(ARM_CC) $(MCU_CFLAGS_hal) $(MCU_TEST_DEFS) $(EXTRA_CFLAGS) -c $< -o $@
$(MCU)/vehicle-test.elf: $(call mcu_objs,$(filter-out $(MCU_TEST_SRC),$(MCU_BOARD_SRC))) \
		$(patsubst %.c,$(MCU)/obj-test/%.o,$(MCU_TEST_SRC)) $(MCU)/libproto.a \
		$(MCU)/libfirmware.a hal/cortexm/$(TARGET).ld
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(ARM_CC) $(MCU_CPU_$(TARGET)) -Os -flto $(MCU_LTO_LINK) -nostartfiles --specs=nano.specs \
		-Wl,--gc-sections -T hal/cortexm/$(TARGET).ld \
		-o $@ $(filter %.o %.a,$^) -lm -lc -lnosys -lgcc

# The tick-cost benchmark for QEMU's mps2-an386 (make bench, tools/bench/
# mcu_tickcost.sh): the host's scenarios on the same libraries and board code.
MCU_CFLAGS_tools := $(MCU_BASE)
MCU_BENCH_SRC := $(addprefix tools/bench/,mcu_tickcost.c scenario.c rig.c) \
	$(addprefix hal/cortexm/,startup.c systick.c uart.c loop_hal.c small_libc.c udivmod64.c \
	semihost.c)
$(MCU)/bench.elf: $(call mcu_objs,$(MCU_BENCH_SRC)) $(MCU)/libfirmware.a hal/cortexm/$(TARGET).ld
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(ARM_CC) $(MCU_CPU_$(TARGET)) -Os -flto $(MCU_LTO_LINK) -nostartfiles --specs=nano.specs \
		-Wl,--gc-sections -T hal/cortexm/$(TARGET).ld \
		-o $@ $(filter %.o %.a,$^) -lm -lc -lnosys -lgcc

# The image's 64-bit division on the board (tests/mcu/divcheck.c), against
# a bitwise one: the objects of the image that carry it, nothing else.
MCU_CFLAGS_tests := $(MCU_BASE)
MCU_DIVCHECK_SRC := tests/mcu/divcheck.c \
	$(addprefix hal/cortexm/,startup.c systick.c small_libc.c udivmod64.c semihost.c)
$(MCU)/divcheck.elf: $(call mcu_objs,$(MCU_DIVCHECK_SRC)) hal/cortexm/$(TARGET).ld
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(ARM_CC) $(MCU_CPU_$(TARGET)) -Os -flto $(MCU_LTO_LINK) -nostartfiles --specs=nano.specs \
		-Wl,--gc-sections -T hal/cortexm/$(TARGET).ld \
		-o $@ $(filter %.o %.a,$^) -lc -lnosys -lgcc

# Every object of the image: none may use floating point.
MCU_IMAGE_OBJS := $(call mcu_objs,$(FW_SRC) $(MCU_PROTO_SRC) $(MCU_BOARD_SRC))

cortexm: $(MCU)/vehicle.elf $(MCU)/libfirmware.a $(MCU)/libproto.a
	$(Q)echo "$(TARGET): $(MCU)/libfirmware.a $(MCU)/libproto.a $(MCU)/vehicle.elf" \
		"($(ARM_CC) -Os, $(MCU_CPU_$(TARGET)))"
	$(Q)$(ARM_SIZE) $(MCU)/vehicle.elf
	$(Q)$(ARM_SIZE) -A $(MCU)/vehicle.elf | awk -v fb=$(MCU_FLASH_BUDGET) -v rb=$(MCU_RAM_BUDGET) \
		-v enforce=$(if $(filter $(TARGET),$(MCU_BUDGET_ENFORCED)),1,0) ' \
		$$1 == ".isr_vector" || $$1 == ".text" || $$1 == ".ARM.exidx" || $$1 == ".ARM.extab" { t += $$2 } \
		$$1 == ".data" { d = $$2 } $$1 == ".bss" { b = $$2 } \
		END { \
			printf "flash (text+data): %d bytes = %.1f KiB (budget %.0f KiB: %s)\n", \
				t + d, (t + d) / 1024, fb / 1024, t + d <= fb ? "met" : "OVER"; \
			printf "static RAM (data+bss): %d bytes = %.1f KiB (budget %.0f KiB: %s);" \
				" plus 4 KiB stack reserved, heap above bss\n", \
				d + b, (d + b) / 1024, rb / 1024, d + b <= rb ? "met" : "OVER"; \
			if (enforce && (t + d > fb || d + b > rb)) { print "over budget"; exit 1 } \
		}'
	$(Q)echo "by origin:"; awk -f hal/cortexm/mapsize.awk $(MCU)/vehicle.map | sort -k3 -n -r
	$(Q)echo "largest RAM users:"; $(ARM_NM) -S --size-sort -t d $(MCU)/vehicle.elf | \
		awk '$$3 ~ /[bBdD]/ { print }' | tail -5 | awk '{ printf "  %6d %s\n", $$2, $$4 }'
	$(Q)hal/cortexm/check_nofloat.sh $(ARM_NM) $(MCU_IMAGE_OBJS)
	$(Q)echo "no floating point in the image: its $(words $(MCU_IMAGE_OBJS)) objects reference" \
		"no soft-float helper"

-include $(shell find $(MCU)/obj -name '*.d' 2>/dev/null)
endif

# Self-test of the floating-point check: a double-using object must be
# rejected, an object calling the integer helper __aeabi_ldivmod accepted.
NOFLOAT_T := $(BUILD)/nofloat-selftest
nofloat-selftest:
	@mkdir -p $(NOFLOAT_T)
	$(Q)$(ARM_CC) -mcpu=cortex-m0 -mthumb -Os -c hal/cortexm/nofloat_test/uses_float.c \
		-o $(NOFLOAT_T)/uses_float.o
	$(Q)$(ARM_CC) -mcpu=cortex-m0 -mthumb -Os -c hal/cortexm/nofloat_test/int_only.c \
		-o $(NOFLOAT_T)/int_only.o
	$(Q)if hal/cortexm/check_nofloat.sh $(ARM_NM) $(NOFLOAT_T)/uses_float.o >$(NOFLOAT_T)/out; then \
		echo "nofloat self-test FAILED: a double multiply was not detected"; exit 1; fi
	$(Q)grep -q '__aeabi_dmul' $(NOFLOAT_T)/out || \
		{ echo "nofloat self-test FAILED: __aeabi_dmul not named"; cat $(NOFLOAT_T)/out; exit 1; }
	$(Q)hal/cortexm/check_nofloat.sh $(ARM_NM) $(NOFLOAT_T)/int_only.o || \
		{ echo "nofloat self-test FAILED: integer helper rejected"; exit 1; }
	$(Q)echo "nofloat self-test: passed (double multiply detected, __aeabi_ldivmod accepted)"

check: nofloat-selftest

.PHONY: mcu-images
mcu-images:
	$(Q)$(MAKE) --no-print-directory TARGET=cortex-m4 BUILD=$(BUILD) cortexm \
		$(BUILD)/cortex-m4/bench.elf $(BUILD)/cortex-m4/divcheck.elf \
		$(BUILD)/cortex-m4/vehicle-cut.elf
	$(Q)$(MAKE) --no-print-directory TARGET=cortex-m4 MCU_KIN=omni BUILD=$(BUILD) cortexm
	$(Q)$(MAKE) --no-print-directory TARGET=cortex-m0 BUILD=$(BUILD) cortexm
	$(Q)$(MAKE) --no-print-directory TARGET=cortex-m4 MCU_DRIVES=modbus BUILD=$(BUILD) cortexm \
		$(BUILD)/cortex-m4-mb/vehicle-test.elf
	$(Q)$(MAKE) --no-print-directory TARGET=cortex-m4 MCU_KIN=omni MCU_DRIVES=modbus BUILD=$(BUILD) \
		cortexm
	$(Q)$(MAKE) --no-print-directory TARGET=cortex-m0 MCU_DRIVES=modbus BUILD=$(BUILD) cortexm

ifneq ($(QEMU),0)
check: mcu-images
endif
