#include <gam/mapper/StopSignal.h>

#include <csignal>

namespace gam::mapper
{
namespace
{
std::atomic<bool> gStopSignal{false};
// A handler may only touch lock-free atomics (or volatile sig_atomic_t).
static_assert(std::atomic<bool>::is_always_lock_free, "the stop flag must be usable in a signal handler");
extern "C" void onStopSignal(int) { gStopSignal.store(true); }
}  // namespace

void installStopSignalHandlers()
{
	// SA_RESTART: a blocking call in a sensor driver's thread that the signal
	// lands in is resumed rather than failing with EINTR; the loops poll the
	// flag, so nothing needs the interruption.
	struct sigaction sa = {};
	sa.sa_handler = onStopSignal;
	sigemptyset(&sa.sa_mask);
	sa.sa_flags = SA_RESTART;
	sigaction(SIGINT, &sa, nullptr);
	sigaction(SIGTERM, &sa, nullptr);
}

const std::atomic<bool>& stopSignalFlag() { return gStopSignal; }
}  // namespace gam::mapper
