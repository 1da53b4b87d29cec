// Ground-aware mapping for MRPT
// Ctrl-C / SIGTERM for ground-aware-mapper: the handler only raises a flag;
// the run loop (offline or live) checks it and ends in its own time.
#pragma once

#include <atomic>

namespace gam::mapper
{
/** Installs handlers for SIGINT and SIGTERM that set stopSignalFlag() and do
 * nothing else: a lock-free atomic store is one of the few things a signal
 * handler may do. Used by the app and, with a real kill(), by the tests. */
void installStopSignalHandlers();
/** The flag the handlers set (false until a signal arrives). */
const std::atomic<bool>& stopSignalFlag();
}  // namespace gam::mapper
