# vehicle-fw: the firmware on the vehicle's Linux computer (docs/linux.md).
#
#   make build/vehicle-fw                      native build
#   make CROSS_COMPILE=aarch64-linux-gnu- BUILD=build-arm64 build/vehicle-fw
#
# hal/linux/ goes into its own library, linked only into vehicle-fw and the
# tests/test_linux_* programs (the Cortex-M build never sees it).

LINUX_SRC := $(filter-out hal/linux/main.c,$(wildcard hal/linux/*.c))
LINUX_LIB := $(BUILD)/liblinux.a
LINUX_LDLIBS := -lgpiod -lmodbus -levdev -lpthread
# libevdev's headers live in their own folder (arch-independent, so the
# native path serves the cross build too).
LINUX_CFLAGS := -I/usr/include/libevdev-1.0

$(call objs,$(LINUX_SRC) hal/linux/main.c) $(BUILD)/obj/tests/test_linux_fw.o: \
	EXTRA_CFLAGS += $(LINUX_CFLAGS)

$(LINUX_LIB): $(call objs,$(LINUX_SRC))

# The platform's main (hal/linux/main.c), as the Cortex-M board has its own.
$(BUILD)/vehicle-fw: $(BUILD)/obj/hal/linux/main.o $(LINUX_LIB) $(HOST_LIBS)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS_HOST) $(LINUX_LDLIBS)

$(BUILD)/tests/test_linux_%: $(BUILD)/obj/tests/test_linux_%.o $(TEST_SUPPORT_LIB) $(LINUX_LIB) \
		$(HOST_LIBS)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ -lcmocka $(LDLIBS_HOST) $(LINUX_LDLIBS) -lutil

all: $(BUILD)/vehicle-fw

# make install [PREFIX=/usr/local] [SYSCONFDIR=/etc] [DESTDIR=]
# Binaries (vehicle-corba when built: it needs omniORB, a cross build leaves
# it out), vehicle-plot and the Python client, the systemd unit, vehicle-sim's
# configuration, example configuration; the configuration in SYSCONFDIR/vehicle
# is written only when absent (never overwritten). docs/linux.md lists what
# goes where; tests/run_install_tests.sh checks the list.
PREFIX ?= /usr/local
SYSCONFDIR ?= /etc
BINDIR := $(PREFIX)/bin
UNITDIR ?= $(PREFIX)/lib/systemd/system
DATADIR := $(PREFIX)/share/vehicle
EXAMPLEDIR := $(DATADIR)/examples
# The Python client (python/vehicleservice) where Debian's /usr/bin/python3
# looks: dist-packages under /usr, the versioned one under other prefixes.
PYVER := $(shell /usr/bin/python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
PYTHONDIR ?= $(if $(filter /usr,$(PREFIX)),/usr/lib/python3/dist-packages,$(PREFIX)/lib/python$(PYVER)/dist-packages)

# Where the programs look for their configuration, fixed at build time:
# vehicle-fw in SYSCONFDIR/vehicle, vehicle-sim in DATADIR or, run from the
# build folder, the checkout's config/ (host_sim/sim_paths.h). The stamp
# holds the values, so that another PREFIX, SYSCONFDIR or BUILD rebuilds
# the two objects.
TREE_REL := $(shell realpath -m --relative-to=$(BUILD) .)
PATHS_STAMP := $(BUILD)/install-paths
$(BUILD)/obj/host_sim/sim_paths.o: \
	EXTRA_CFLAGS += -DVEHICLE_DATADIR='"$(DATADIR)"' -DVEHICLE_TREE_CONFIG='"$(TREE_REL)/config"'
$(BUILD)/obj/hal/linux/main.o: EXTRA_CFLAGS += -DVEHICLE_SYSCONFDIR='"$(SYSCONFDIR)"'
$(BUILD)/obj/host_sim/sim_paths.o $(BUILD)/obj/hal/linux/main.o: $(PATHS_STAMP)
.PHONY: FORCE
FORCE:
$(PATHS_STAMP): FORCE
	@mkdir -p $(dir $@)
	$(Q)printf '%s\n' '$(DATADIR)' '$(TREE_REL)' '$(SYSCONFDIR)' >$@.new
	$(Q)if cmp -s $@.new $@; then rm $@.new; else mv $@.new $@; fi

.PHONY: install
install: $(BUILD)/vehicle-fw $(BUILD)/vehiclectl $(BUILD)/vehicle-sim
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(UNITDIR) $(DESTDIR)$(DATADIR) \
		$(DESTDIR)$(EXAMPLEDIR) $(DESTDIR)$(SYSCONFDIR)/vehicle \
		$(DESTDIR)$(PYTHONDIR)/vehicleservice
	install -m 755 $(BUILD)/vehicle-fw $(BUILD)/vehiclectl $(BUILD)/vehicle-sim \
		$(DESTDIR)$(BINDIR)/
	[ ! -e $(BUILD)/vehicle-corba ] || install -m 755 $(BUILD)/vehicle-corba $(DESTDIR)$(BINDIR)/
	install -m 644 python/vehicleservice/*.py $(DESTDIR)$(PYTHONDIR)/vehicleservice/
	install -m 755 tools/vehicle-plot $(DESTDIR)$(BINDIR)/vehicle-plot
	sed -e 's|@BINDIR@|$(BINDIR)|g' -e 's|@SYSCONFDIR@|$(SYSCONFDIR)|g' \
		tools/systemd/vehicle-fw.service >$(DESTDIR)$(UNITDIR)/vehicle-fw.service
	chmod 644 $(DESTDIR)$(UNITDIR)/vehicle-fw.service
	install -m 644 config/vehicle.xml config/io.xml $(DESTDIR)$(DATADIR)/
	install -m 644 config/vehicle-linux.xml config/vehicle.xml config/vehicle-jerk.xml \
		config/vehicle-omni.xml config/vehicle-omni-jerk.xml config/io.xml \
		$(DESTDIR)$(EXAMPLEDIR)/
	[ -e $(DESTDIR)$(SYSCONFDIR)/vehicle/vehicle.xml ] || \
		install -m 644 config/vehicle-linux.xml $(DESTDIR)$(SYSCONFDIR)/vehicle/vehicle.xml
	[ -e $(DESTDIR)$(SYSCONFDIR)/vehicle/io.xml ] || \
		install -m 644 config/io.xml $(DESTDIR)$(SYSCONFDIR)/vehicle/io.xml

CHECK_SUITES += tests/run_install_tests.sh

# Modbus RTU drive simulator for the tests (host_sim/devices/), on the
# drive profiles of hal/modbus/ (in the host library).
$(BUILD)/mbdrive-sim: $(BUILD)/obj/host_sim/devices/mbdrive_sim_main.o $(HOST_LIB)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^ -lmodbus

all: $(BUILD)/mbdrive-sim

# Virtual uinput joystick for the QEMU guest tests (host_sim/devices/).
$(BUILD)/ujoy: $(BUILD)/obj/host_sim/devices/ujoy_main.o
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^

all: $(BUILD)/ujoy

# CiA 402 drive simulator on SocketCAN for the QEMU guest tests (host_sim/devices/).
$(BUILD)/cia402-sim: $(BUILD)/obj/host_sim/devices/cia402sim_main.o
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CC) $(LDFLAGS) -o $@ $^

all: $(BUILD)/cia402-sim
