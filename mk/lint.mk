# Static analysis: `make lint` must end with zero findings.
#
#   cppcheck    warning, style, performance, portability on firmware/, proto/,
#               hal/, host_sim/; suppressions with reasons in
#               tools/lint/cppcheck.supp
#   clang-tidy  the checks of .clang-tidy (reasons there), warnings as errors
#   clang       -Wconversion -Wshadow -Wsign-conversion -Werror on firmware/ and
#               proto/ (the gcc build enforces the same; clang sees more)
#   clang-format every tracked C file follows .clang-format (`make format` fixes)
#   client      vehiclectl links no firmware object (nm): the client library
#               uses the command table and the encodings, never the unit
#   includes    the folder rules of docs/architecture.md (tools/lint/includes.py)
#   fnsize      no function of firmware/ over 80 body lines or nested deeper
#               than 4, no file over 800 lines (tools/lint/fnsize.py)
#   objdeps     no cycle of symbol use among the objects of firmware/, nor
#               among those of proto/: two files that use each other's
#               symbols, or a lower layer that calls back up
#               (tools/lint/objdeps.py, with its self-test)
# Every tracked C file is in one of the sets below:
#   LINT_SRC       host code, all checks: firmware/, proto/, hal/posix/,
#                  hal/linux/, host_sim/ (devices too), the tools and
#                  benchmarks, the guest probe
#   LINT_MCU_SRC   hal/cortexm/ and the board benchmark: cppcheck, and
#                  clang-tidy for the Cortex-M4 target (LINT_MCU_DEFS)
#   LINT_TEST_SRC  tests/: cppcheck; not clang-tidy, whose checks misread
#                  cmocka's macros; they build with -Wall -Wextra -Werror
#   the gpio test chip (tools/qemu/gpio-testchip), a kernel module: cppcheck
#                  without the kernel's headers; kbuild compiles it with the
#                  kernel's warnings
LINT_MCU_SRC := $(wildcard hal/cortexm/*.c hal/cortexm/nofloat_test/*.c) tools/bench/mcu_tickcost.c
LINT_SRC := $(FW_SRC) $(PROTO_SRC) $(HOST_SRC) $(SIM_SRC) $(wildcard host_sim/*_main.c) \
	$(wildcard hal/linux/*.c host_sim/devices/*.c tools/*.c tools/ref/*.c) \
	$(filter-out $(LINT_MCU_SRC),$(wildcard tools/bench/*.c)) tests/qemu/uinput_probe.c
LINT_TEST_SRC := $(filter-out tests/qemu/uinput_probe.c,$(wildcard tests/*.c tests/*/*.c))
LINT_KMOD_SRC := tools/qemu/gpio-testchip/gpio_testchip.c
LINT_DEFS := -std=c11 -I. -D_GNU_SOURCE -I/usr/include/libevdev-1.0
LINT_MCU_DEFS := -std=c11 -I. --target=arm-none-eabi -mcpu=cortex-m4 -mthumb -ffreestanding \
	-DMOTION_QUEUE_LEN=16 -DVS_KIN_ONLY=0 -isystem /usr/lib/arm-none-eabi/include
CLANG ?= clang

.PHONY: lint lint-cppcheck lint-tidy lint-warnings lint-format lint-client lint-includes lint-sets lint-fnsize \
	lint-objdeps

lint: lint-sets lint-format lint-includes lint-cppcheck lint-warnings lint-tidy lint-client lint-fnsize \
	lint-objdeps

# A C file that no set names fails: a new folder cannot slip past lint.
lint-sets:
	@echo "  SETS    every tracked C file is analysed"
	$(Q)printf '%s\n' $(LINT_SRC) $(LINT_MCU_SRC) $(LINT_TEST_SRC) $(LINT_KMOD_SRC) | \
		LC_ALL=C sort -u >$(BUILD)/lint-sets
	$(Q)miss=$$(git ls-files '*.c' | LC_ALL=C sort | LC_ALL=C comm -23 - $(BUILD)/lint-sets); \
	if [ -n "$$miss" ]; then echo "not in any lint set:" $$miss; exit 1; fi

# What may include what (docs/architecture.md); the self-test first proves
# that each rule catches its violation.
lint-includes:
	@echo "  INCLUDES folder rules"
	$(Q)python3 tools/lint/includes.py --self-test
	$(Q)python3 tools/lint/includes.py .

FNSIZE_SRC := $(FW_SRC) $(wildcard firmware/*.h)

lint-fnsize:
	@echo "  FNSIZE  firmware: 80 body lines, nesting depth 4, 800 lines a file"
	$(Q)python3 tools/lint/fnsize.py $(FNSIZE_SRC)

# The objects of the sources (not every .o in the folder: a file removed
# leaves its object behind).
lint-objdeps: $(call objs,$(FW_SRC) $(PROTO_SRC))
	@echo "  OBJDEPS no cycle among the objects of firmware/, of proto/"
	$(Q)python3 tools/lint/objdeps.py --self-test
	$(Q)python3 tools/lint/objdeps.py firmware $(call objs,$(FW_SRC))
	$(Q)python3 tools/lint/objdeps.py proto $(call objs,$(PROTO_SRC))

# Every global symbol firmware/ defines, looked for in vehiclectl.
lint-client: $(BUILD)/vehiclectl $(FW_LIB)
	@echo "  NM      vehiclectl links no firmware"
	$(Q)nm -g --defined-only $(FW_LIB) | awk 'NF == 3 { print $$3 }' | sort -u >$(BUILD)/fw-symbols
	$(Q)hit=$$(nm -g --defined-only $(BUILD)/vehiclectl | awk 'NF == 3 { print $$3 }' | \
		sort -u | comm -12 - $(BUILD)/fw-symbols); \
	if [ -n "$$hit" ]; then echo "vehiclectl links firmware:" $$hit; exit 1; fi

lint-format:
	@echo "  FORMAT  .clang-format"
	$(Q)git ls-files '*.c' '*.h' | xargs clang-format --dry-run -Werror

lint-cppcheck:
	@echo "  CPPCHECK $(words $(LINT_SRC) $(LINT_MCU_SRC) $(LINT_TEST_SRC) $(LINT_KMOD_SRC)) files"
	$(Q)cppcheck --quiet --std=c11 --enable=warning,style,performance,portability \
		--inline-suppr --suppressions-list=tools/lint/cppcheck.supp --error-exitcode=1 \
		-D_GNU_SOURCE -I. -I/usr/include/libevdev-1.0 $(LINT_SRC) $(LINT_MCU_SRC) \
		$(LINT_TEST_SRC)
	$(Q)cppcheck --quiet --std=c11 --enable=warning,style,performance,portability \
		--inline-suppr --suppressions-list=tools/lint/cppcheck.supp --error-exitcode=1 \
		$(LINT_KMOD_SRC)

lint-tidy:
	@echo "  TIDY    $(words $(LINT_SRC) $(LINT_MCU_SRC)) files"
	$(Q)fail=0; for f in $(LINT_SRC); do \
		clang-tidy --quiet $$f -- $(LINT_DEFS) 2>/dev/null || fail=1; \
	done; for f in $(LINT_MCU_SRC); do \
		clang-tidy --quiet $$f -- $(LINT_MCU_DEFS) 2>/dev/null || fail=1; \
	done; exit $$fail

lint-warnings:
	@echo "  CLANG   -Wconversion -Wshadow firmware proto"
	$(Q)for f in $(FW_SRC); do \
		$(CLANG) $(LINT_DEFS) -fsyntax-only -ffreestanding $(WARN) $(STRICT) $$f || exit 1; done
	$(Q)for f in $(PROTO_SRC); do \
		$(CLANG) $(LINT_DEFS) -fsyntax-only $(WARN) $(STRICT) $$f || exit 1; done
