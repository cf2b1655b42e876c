# vehicle-fw: the firmware on the vehicle's Linux computer (docs/linux.md).
#
#   make build/vehicle-fw                      native build
#   make CROSS_COMPILE=aarch64-linux-gnu- BUILD=build-arm64 build/vehicle-fw
#
# hal/linux/ goes into its own library, linked only into vehicle-fw and the
# tests/test_linux_* programs (the Cortex-M build never sees it).

LINUX_SRC := $(wildcard hal/linux/*.c)
LINUX_LIB := $(BUILD)/liblinux.a
LINUX_LDLIBS := -lgpiod

$(LINUX_LIB): $(call objs,$(LINUX_SRC))

# The tools pattern names the binary after tools/vehicle_fw_main.c; the
# installed name has a dash.
$(BUILD)/vehicle_fw: $(BUILD)/obj/tools/vehicle_fw_main.o $(LINUX_LIB) $(HOST_LIBS)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS_HOST) $(LINUX_LDLIBS)

$(BUILD)/vehicle-fw: $(BUILD)/vehicle_fw
	$(Q)cp -f $< $@

$(BUILD)/tests/test_linux_%: $(BUILD)/obj/tests/test_linux_%.o $(TEST_SUPPORT_LIB) $(LINUX_LIB) \
		$(HOST_LIBS)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ -lcmocka $(LDLIBS_HOST) $(LINUX_LDLIBS) -lutil

all: $(BUILD)/vehicle-fw
