// vehicle-corba: serves VehicleService over CORBA (omniORB) from the IDL of
// the specification's appendix, and forwards every call to a unit through the
// C client library (proto/client/client.h) over a serial port (binary frames or the
// text console) or CAN. docs/corba.md has the options and the exception map.
//
//   vehicle-corba --port /dev/ttyUSB0 [--name VehicleService] [--ior]
//       -ORBInitRef NameService=corbaname::127.0.0.1:2809
//
// One unit, one client: calls are serialised by a mutex, each bounded by
// the link's timeout times its attempts, so no call waits forever.
#include <errno.h>
#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mutex>
#include <string>

#include "VehicleService.hh"

extern "C" {
#include "proto/client/client.h"
}

namespace
{

// Minor codes of the system exceptions: the client library's status,
// negated (docs/corba.md).
CORBA::ULong minor_of(int e)
{
	return static_cast<CORBA::ULong>(-e);
}

struct link_opts {
	const char *port = nullptr;
	const char *can = nullptr;
	bool console = false;
	unsigned long baud = VC_DEFAULT_BAUD;
	unsigned long node = 1;
	unsigned long timeout_ms = VC_DEFAULT_TIMEOUT_MS;
	unsigned long retries = VC_DEFAULT_RETRIES;
};

// The unit behind the gateway: opens the link on first use and again after
// the port failed (a USB adapter unplugged and back).
class unit_link
{
      public:
	explicit unit_link(const link_opts &o) : o_(o) {}
	~unit_link()
	{
		if (open_)
			vc_close(&c_);
	}
	unit_link(const unit_link &) = delete;
	unit_link &operator=(const unit_link &) = delete;

	// Returns the client, ready, or throws TRANSIENT (not sent at all).
	vc_client_t *get()
	{
		if (open_)
			return &c_;
		int e = o_.can	     ? vc_open_can(&c_, o_.can, static_cast<unsigned>(o_.node))
			: o_.console ? vc_open_console(&c_, o_.port, static_cast<unsigned>(o_.baud))
				     : vc_open_serial(&c_, o_.port, static_cast<unsigned>(o_.baud));
		if (e != VC_OK)
			throw CORBA::TRANSIENT(minor_of(e), CORBA::COMPLETED_NO);
		c_.timeout_ms = static_cast<unsigned>(o_.timeout_ms);
		c_.retries = static_cast<unsigned>(o_.retries);
		open_ = true;
		return &c_;
	}

	// Turns a client status into the call's outcome: nothing for VC_OK,
	// else the system exception of docs/corba.md.
	void check(int e)
	{
		switch (e) {
		case VC_OK:
			return;
		case VC_E_TIMEOUT:
		case VC_E_CRC:
			throw CORBA::TRANSIENT(minor_of(e), CORBA::COMPLETED_MAYBE);
		case VC_E_LINK:
			vc_close(&c_);
			open_ = false;
			throw CORBA::TRANSIENT(minor_of(e), CORBA::COMPLETED_MAYBE);
		case VC_E_NAK:
			if (c_.nak == WIRE_ST_OPCODE)
				throw CORBA::NO_IMPLEMENT(minor_of(e), CORBA::COMPLETED_NO);
			throw CORBA::MARSHAL(minor_of(e), CORBA::COMPLETED_NO);
		case VC_E_PROTO:
			throw CORBA::MARSHAL(minor_of(e), CORBA::COMPLETED_MAYBE);
		case VC_E_ARG:
		case VC_E_REMOTE:
			throw CORBA::BAD_PARAM(minor_of(e), CORBA::COMPLETED_NO);
		case VC_E_UNSUPPORTED:
			throw CORBA::NO_IMPLEMENT(minor_of(e), CORBA::COMPLETED_NO);
		default:
			throw CORBA::INTERNAL(minor_of(e), CORBA::COMPLETED_MAYBE);
		}
	}

	std::mutex mu;

      private:
	link_opts o_;
	vc_client_t c_{};
	bool open_ = false;
};

vs_point_t to_c(const Point &p)
{
	return vs_point_t{p.x, p.y};
}
vs_position_t to_c(const Position &p)
{
	return vs_position_t{p.x, p.y, p.theta};
}
vs_velocity_t to_c(const Velocity &v)
{
	return vs_velocity_t{v.translation, v.rotation};
}

AlarmType alarm_type(uint8_t t)
{
	// The IDL's enumerators live in the global scope (no module).
	switch (t) {
	case VS_ALARM_FAULT:
		return ::fault;
	case VS_ALARM_WARNING:
		return ::warning;
	default:
		return ::unknown;
	}
}

// Runs one library call under the link's lock and returns the unit's
// boolean. f(client, &ret) returns the client status.
template <typename F> CORBA::Boolean forward(unit_link &u, F f)
{
	std::lock_guard<std::mutex> lock(u.mu);
	vc_client_t *c = u.get();
	bool r = false;
	u.check(f(c, &r));
	return r;
}

class VehicleServiceImpl : public POA_VehicleService
{
      public:
	explicit VehicleServiceImpl(unit_link &u) : u_(u) {}

	CORBA::Boolean clearAlarm() override
	{
		return forward(u_, [](vc_client_t *c, bool *r) { return vc_clearAlarm(c, r); });
	}
	CORBA::Boolean getAccelerationLimit(CORBA::Double &accLimitT,
					    CORBA::Double &accLimitR) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_getAccelerationLimit(c, r, &accLimitT, &accLimitR);
		});
	}
	CORBA::Boolean getActiveAlarm(CORBA::Short numOfAlarm, CORBA::Short &numOfActiveAlarm,
				      SeqAlarm_out activeAlarms) override
	{
		// The unit sends at most VS_ALARM_LIST_MAX whatever was asked.
		vs_alarm_t a[VS_ALARM_LIST_MAX];
		uint16_t n = 0;
		int16_t active = 0;
		CORBA::Boolean r = forward(u_, [&](vc_client_t *c, bool *ret) {
			return vc_getActiveAlarm(c, ret, numOfAlarm, &active, a, &n);
		});
		SeqAlarm_var seq = new SeqAlarm(n);
		seq->length(n);
		for (uint16_t i = 0; i < n; i++) {
			seq[i].code = a[i].code;
			seq[i].type = alarm_type(a[i].type);
			seq[i].source = CORBA::string_dup(a[i].source);
		}
		numOfActiveAlarm = active;
		activeAlarms = seq._retn();
		return r;
	}
	CORBA::Boolean getBatteryVoltage(CORBA::Double &voltage) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_getBatteryVoltage(c, r, &voltage);
		});
	}
	CORBA::Boolean getDefaultAcceleration(Acceleration &defaultAccel) override
	{
		vs_velocity_t v{};
		CORBA::Boolean r = forward(u_, [&](vc_client_t *c, bool *ret) {
			return vc_getDefaultAcceleration(c, ret, &v);
		});
		defaultAccel.translation = v.translation;
		defaultAccel.rotation = v.rotation;
		return r;
	}
	CORBA::Boolean getDefaultVelocity(Velocity &defaultVel) override
	{
		vs_velocity_t v{};
		CORBA::Boolean r = forward(u_, [&](vc_client_t *c, bool *ret) {
			return vc_getDefaultVelocity(c, ret, &v);
		});
		defaultVel.translation = v.translation;
		defaultVel.rotation = v.rotation;
		return r;
	}
	CORBA::Boolean getIFVersion(CORBA::String_out version) override
	{
		std::string s;
		CORBA::Boolean r = forward(u_, [&](vc_client_t *c, bool *ret) {
			const char *p = nullptr;
			int e = vc_getIFVersion(c, ret, &p);
			s = p ? p : "";
			return e;
		});
		version = CORBA::string_dup(s.c_str());
		return r;
	}
	CORBA::Boolean getInput(CORBA::ULong ioid, CORBA::ULong &input) override
	{
		uint32_t v = 0;
		CORBA::Boolean r = forward(
		    u_, [&](vc_client_t *c, bool *ret) { return vc_getInput(c, ret, ioid, &v); });
		input = v;
		return r;
	}
	CORBA::Boolean getPosition(Position &pos) override
	{
		vs_position_t p{};
		CORBA::Boolean r = forward(
		    u_, [&](vc_client_t *c, bool *ret) { return vc_getPosition(c, ret, &p); });
		pos.x = p.x;
		pos.y = p.y;
		pos.theta = p.theta;
		return r;
	}
	CORBA::Boolean getServoStatus(CORBA::ULong axisid, CORBA::Boolean &status) override
	{
		bool s = false;
		CORBA::Boolean r = forward(u_, [&](vc_client_t *c, bool *ret) {
			return vc_getServoStatus(c, ret, axisid, &s);
		});
		status = s;
		return r;
	}
	CORBA::Boolean getState(CORBA::Short &state, CORBA::String_out Msg) override
	{
		char msg[VS_STATE_MSG_MAX] = "";
		int16_t st = 0;
		CORBA::Boolean r = forward(
		    u_, [&](vc_client_t *c, bool *ret) { return vc_getState(c, ret, &st, msg); });
		state = st;
		Msg = CORBA::string_dup(msg);
		return r;
	}
	CORBA::Boolean getVelocityLimit(CORBA::Double &velLimitT, CORBA::Double &velLimitR) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_getVelocityLimit(c, r, &velLimitT, &velLimitR);
		});
	}
	CORBA::Boolean getVersion(CORBA::String_out ver) override
	{
		std::string s;
		CORBA::Boolean r = forward(u_, [&](vc_client_t *c, bool *ret) {
			const char *p = nullptr;
			int e = vc_getVersion(c, ret, &p);
			s = p ? p : "";
			return e;
		});
		ver = CORBA::string_dup(s.c_str());
		return r;
	}
	CORBA::Boolean moveCircularRel(const Point &centerPoint, CORBA::Double theta) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_moveCircularRel(c, r, to_c(centerPoint), theta);
		});
	}
	CORBA::Boolean moveContinuousRel(const Position &pos) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_moveContinuousRel(c, r, to_c(pos));
		});
	}
	CORBA::Boolean moveCruiseAbs(const Point &cruisePoint) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_moveCruiseAbs(c, r, to_c(cruisePoint));
		});
	}
	CORBA::Boolean moveForward(CORBA::Double x_) override
	{
		return forward(u_,
			       [&](vc_client_t *c, bool *r) { return vc_moveForward(c, r, x_); });
	}
	CORBA::Boolean moveJog(CORBA::Double xVel, CORBA::Double yVel,
			       CORBA::Double thetaVel) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_moveJog(c, r, xVel, yVel, thetaVel);
		});
	}
	CORBA::Boolean moveLinearAbs(const Position &pos) override
	{
		return forward(
		    u_, [&](vc_client_t *c, bool *r) { return vc_moveLinearAbs(c, r, to_c(pos)); });
	}
	CORBA::Boolean moveLinearRel(const Position &pos) override
	{
		return forward(
		    u_, [&](vc_client_t *c, bool *r) { return vc_moveLinearRel(c, r, to_c(pos)); });
	}
	CORBA::Boolean moveTurn(CORBA::Double theta_) override
	{
		return forward(u_,
			       [&](vc_client_t *c, bool *r) { return vc_moveTurn(c, r, theta_); });
	}
	CORBA::Boolean pause() override
	{
		return forward(u_, [](vc_client_t *c, bool *r) { return vc_pause(c, r); });
	}
	CORBA::Boolean resume() override
	{
		return forward(u_, [](vc_client_t *c, bool *r) { return vc_resume(c, r); });
	}
	CORBA::Boolean setAcceleration(const Velocity &accel) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_setAcceleration(c, r, to_c(accel));
		});
	}
	CORBA::Boolean setDigitalSensorLock(CORBA::Boolean OnOff) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_setDigitalSensorLock(c, r, OnOff);
		});
	}
	CORBA::Boolean setJogTimeout(CORBA::Short timeout) override
	{
		return forward(
		    u_, [&](vc_client_t *c, bool *r) { return vc_setJogTimeout(c, r, timeout); });
	}
	CORBA::Boolean setJoystick(CORBA::Boolean OnOff) override
	{
		return forward(
		    u_, [&](vc_client_t *c, bool *r) { return vc_setJoystick(c, r, OnOff); });
	}
	CORBA::Boolean setOutput(CORBA::ULong ioid, CORBA::ULong output, CORBA::ULong mask) override
	{
		return forward(u_, [&](vc_client_t *c, bool *r) {
			return vc_setOutput(c, r, ioid, output, mask);
		});
	}
	CORBA::Boolean setPosition(const Position &pos) override
	{
		return forward(
		    u_, [&](vc_client_t *c, bool *r) { return vc_setPosition(c, r, to_c(pos)); });
	}
	CORBA::Boolean setPower(CORBA::Boolean OnOff) override
	{
		return forward(u_,
			       [&](vc_client_t *c, bool *r) { return vc_setPower(c, r, OnOff); });
	}
	CORBA::Boolean setServo(CORBA::Boolean OnOff) override
	{
		return forward(u_,
			       [&](vc_client_t *c, bool *r) { return vc_setServo(c, r, OnOff); });
	}
	CORBA::Boolean setVelocity(const Velocity &vel) override
	{
		return forward(
		    u_, [&](vc_client_t *c, bool *r) { return vc_setVelocity(c, r, to_c(vel)); });
	}
	CORBA::Boolean stop() override
	{
		return forward(u_, [](vc_client_t *c, bool *r) { return vc_stop(c, r); });
	}
	CORBA::Boolean unlock() override
	{
		return forward(u_, [](vc_client_t *c, bool *r) { return vc_unlock(c, r); });
	}

      private:
	unit_link &u_;
};

void usage(FILE *f)
{
	fputs("usage: vehicle-corba LINK [options] [-ORB... options]\n"
	      "links (one of):\n"
	      "  --port DEV       serial port, binary frames (docs/protocol.md)\n"
	      "  --console        speak the text console on the port instead of frames\n"
	      "  --baud N         line speed (default 115200)\n"
	      "  --can IFACE      SocketCAN interface (docs/can.md)\n"
	      "  --node N         CAN node id of the unit (default 1)\n"
	      "options:\n"
	      "  --timeout MS     per attempt (default 500)\n"
	      "  --retries N      further attempts after a timeout (default 2)\n"
	      "  --name NAME      naming service name, \"a/b.kind\" form (default VehicleService)\n"
	      "  --no-naming      do not register with a naming service\n"
	      "  --ior            print the object's IOR on stdout once it is served\n"
	      "  --ior-file FILE  write the IOR to FILE\n"
	      "The object key is \"VehicleService\": with -ORBendPoint giop:tcp:HOST:PORT it is\n"
	      "also corbaloc::HOST:PORT/VehicleService. The naming service comes from\n"
	      "-ORBInitRef NameService=... (or omniORB.cfg).\n",
	      f);
}

bool parse_ulong(const char *s, unsigned long max, unsigned long *out)
{
	char *end;

	errno = 0;
	*out = strtoul(s, &end, 10);
	return *s && *s != '-' && !*end && errno == 0 && *out <= max;
}

// Binds obj under name (creating the intermediate contexts).
void register_name(CORBA::ORB_ptr orb, const char *name, CORBA::Object_ptr obj)
{
	CORBA::Object_var o = orb->resolve_initial_references("NameService");
	CosNaming::NamingContextExt_var root = CosNaming::NamingContextExt::_narrow(o);
	if (CORBA::is_nil(root))
		throw CORBA::OBJECT_NOT_EXIST(0, CORBA::COMPLETED_NO);
	CosNaming::Name_var n = root->to_name(name);
	CosNaming::NamingContext_var ctx = CosNaming::NamingContext::_duplicate(root);
	for (CORBA::ULong i = 0; i + 1 < n->length(); i++) {
		CosNaming::Name part;
		part.length(1);
		part[0] = n[i];
		try {
			ctx = ctx->bind_new_context(part);
		} catch (CosNaming::NamingContext::AlreadyBound &) {
			CORBA::Object_var sub = ctx->resolve(part);
			ctx = CosNaming::NamingContext::_narrow(sub);
			if (CORBA::is_nil(ctx))
				throw CosNaming::NamingContext::NotFound(
				    CosNaming::NamingContext::not_context, part);
		}
	}
	CosNaming::Name last;
	last.length(1);
	last[0] = n[n->length() - 1];
	ctx->rebind(last, obj);
}

void unregister_name(CORBA::ORB_ptr orb, const char *name)
{
	try {
		CORBA::Object_var o = orb->resolve_initial_references("NameService");
		CosNaming::NamingContextExt_var root = CosNaming::NamingContextExt::_narrow(o);
		if (!CORBA::is_nil(root)) {
			CosNaming::Name_var n = root->to_name(name);
			root->unbind(n);
		}
	} catch (CORBA::Exception &e) {
		fprintf(stderr, "vehicle-corba: unbinding %s: %s\n", name, e._name());
	}
}

// Asks the unit once at start-up so that a wrong port or an incompatible
// unit shows in the log; the gateway serves either way (units come and go).
void probe(unit_link &u)
{
	try {
		std::lock_guard<std::mutex> lock(u.mu);
		vc_client_t *c = u.get();
		unsigned ver = 0, ops = 0;
		uint16_t crc = 0;
		int e = vc_info(c, &ver, &crc, &ops);

		if (e != VC_OK) {
			fprintf(stderr,
				"vehicle-corba: the unit did not answer (%s); serving anyway\n",
				vc_strerror(e));
			if (e == VC_E_LINK)
				u.check(e);
			return;
		}
		if (ver != CMD_PROTO_VERSION || crc != cmd_table_crc())
			fprintf(
			    stderr,
			    "vehicle-corba: the unit's command table differs (protocol %u, table "
			    "0x%04X; this gateway %d, 0x%04X)\n",
			    ver, crc, CMD_PROTO_VERSION, static_cast<unsigned>(cmd_table_crc()));
		const char *ifv = nullptr;
		bool r = false;
		if (vc_getIFVersion(c, &r, &ifv) == VC_OK && ifv &&
		    strcmp(ifv, VehicleService::ifVersion) != 0)
			fprintf(stderr, "vehicle-corba: the unit reports \"%s\", the IDL \"%s\"\n",
				ifv, VehicleService::ifVersion);
	} catch (CORBA::SystemException &) {
		fprintf(stderr, "vehicle-corba: the link is not usable yet; serving anyway\n");
	}
}

} // namespace

int main(int argc, char **argv)
{
	// Signals are taken by sigwait in main; every ORB thread inherits the mask.
	sigset_t sigs;
	sigemptyset(&sigs);
	sigaddset(&sigs, SIGINT);
	sigaddset(&sigs, SIGTERM);
	pthread_sigmask(SIG_BLOCK, &sigs, nullptr);
	signal(SIGPIPE, SIG_IGN);

	CORBA::ORB_var orb;
	try {
		orb = CORBA::ORB_init(argc, argv); // takes the -ORB options out of argv
	} catch (CORBA::Exception &e) {
		fprintf(stderr, "vehicle-corba: ORB_init: %s\n", e._name());
		return 2;
	}

	link_opts lo;
	const char *name = "VehicleService", *ior_file = nullptr;
	bool naming = true, print_ior = false;
	enum {
		O_PORT = 1,
		O_CONSOLE,
		O_BAUD,
		O_CAN,
		O_NODE,
		O_TIMEOUT,
		O_RETRIES,
		O_NAME,
		O_NO_NAMING,
		O_IOR,
		O_IOR_FILE,
		O_HELP
	};
	static const struct option opts[] = {
	    {"port", required_argument, nullptr, O_PORT},
	    {"console", no_argument, nullptr, O_CONSOLE},
	    {"baud", required_argument, nullptr, O_BAUD},
	    {"can", required_argument, nullptr, O_CAN},
	    {"node", required_argument, nullptr, O_NODE},
	    {"timeout", required_argument, nullptr, O_TIMEOUT},
	    {"retries", required_argument, nullptr, O_RETRIES},
	    {"name", required_argument, nullptr, O_NAME},
	    {"no-naming", no_argument, nullptr, O_NO_NAMING},
	    {"ior", no_argument, nullptr, O_IOR},
	    {"ior-file", required_argument, nullptr, O_IOR_FILE},
	    {"help", no_argument, nullptr, O_HELP},
	    {nullptr, 0, nullptr, 0},
	};
	int o;
	while ((o = getopt_long(argc, argv, "", opts, nullptr)) != -1) {
		switch (o) {
		case O_PORT:
			lo.port = optarg;
			break;
		case O_CONSOLE:
			lo.console = true;
			break;
		case O_CAN:
			lo.can = optarg;
			break;
		case O_NAME:
			name = optarg;
			break;
		case O_NO_NAMING:
			naming = false;
			break;
		case O_IOR:
			print_ior = true;
			break;
		case O_IOR_FILE:
			ior_file = optarg;
			break;
		case O_BAUD:
		case O_NODE:
		case O_TIMEOUT:
		case O_RETRIES: {
			unsigned long *dst = o == O_BAUD      ? &lo.baud
					     : o == O_NODE    ? &lo.node
					     : o == O_TIMEOUT ? &lo.timeout_ms
							      : &lo.retries;
			unsigned long max = o == O_BAUD ? 4000000 : o == O_NODE ? 127 : 60000;

			if (!parse_ulong(optarg, max, dst) || (o == O_NODE && *dst == 0) ||
			    (o == O_TIMEOUT && *dst == 0) || (o == O_RETRIES && *dst > 10)) {
				fprintf(stderr, "vehicle-corba: bad number %s\n", optarg);
				return 2;
			}
			break;
		}
		case O_HELP:
			usage(stdout);
			return 0;
		default:
			usage(stderr);
			return 2;
		}
	}
	if (optind < argc || !lo.port == !lo.can || (lo.console && !lo.port) || !*name) {
		usage(stderr);
		return 2;
	}

	unit_link unit(lo);
	int rc = 0;
	try {
		probe(unit);

		// The INS POA gives the object a fixed key, so its corbaloc and
		// (with a fixed endpoint) its IOR stay the same across restarts.
		CORBA::Object_var obj = orb->resolve_initial_references("omniINSPOA");
		PortableServer::POA_var poa = PortableServer::POA::_narrow(obj);
		PortableServer::ObjectId_var oid =
		    PortableServer::string_to_ObjectId("VehicleService");
		PortableServer::Servant_var<VehicleServiceImpl> servant =
		    new VehicleServiceImpl(unit);
		poa->activate_object_with_id(oid, servant);
		obj = poa->id_to_reference(oid);
		PortableServer::POAManager_var pm = poa->the_POAManager();
		pm->activate();

		CORBA::String_var ior = orb->object_to_string(obj);
		if (ior_file) {
			FILE *f = fopen(ior_file, "w");
			if (!f || fprintf(f, "%s\n", static_cast<const char *>(ior)) < 0 ||
			    fclose(f) != 0) {
				fprintf(stderr, "vehicle-corba: %s: %s\n", ior_file,
					strerror(errno));
				return 1;
			}
		}
		if (naming) {
			try {
				register_name(orb, name, obj);
			} catch (CORBA::Exception &e) {
				fprintf(stderr, "vehicle-corba: naming service: %s\n", e._name());
				return 1;
			}
			fprintf(stderr, "vehicle-corba: registered as %s\n", name);
		}
		if (print_ior) {
			printf("%s\n", static_cast<const char *>(ior));
			fflush(stdout);
		}
		fprintf(stderr, "vehicle-corba: serving %s on %s\n",
			lo.can	     ? "CAN"
			: lo.console ? "console"
				     : "frames",
			lo.can ? lo.can : lo.port);

		int sig = 0;
		while (sigwait(&sigs, &sig) != 0) {
		}
		if (naming)
			unregister_name(orb, name);
		// The ORB does not destroy the INS POA by itself.
		poa->destroy(true, true);
		orb->shutdown(true);
	} catch (CORBA::Exception &e) {
		fprintf(stderr, "vehicle-corba: %s\n", e._name());
		rc = 1;
	}
	orb->destroy();
	return rc;
}
