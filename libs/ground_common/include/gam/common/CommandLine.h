// Ground-aware mapping for MRPT -- command lines of the programs: one
// behaviour for --help, --version and parse errors (MRPT's TCLAP).
#pragma once

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <iostream>
#include <string>

namespace gam
{
/** Keeps TCLAP's parse error for a one-line message instead of its usage dump. */
class QuietFailureOutput : public TCLAP::StdOutput
{
   public:
	std::string error;
	void failure(TCLAP::CmdLineInterface&, TCLAP::ArgException& e) override
	{
		error = e.argId() + ": " + e.error();
		for (auto& c : error)
			if (c == '\n' || c == '\r') c = ' ';
	}
};

/** Parses the command line. Returns -1 to go on; otherwise the program should
 * exit with the returned code: 0 after --help or --version (printed), 2 after
 * a parse error (one line on stderr: "<prog>: error: <what> (see --help)"). */
inline int parseCommandLine(TCLAP::CmdLine& cmd, int argc, char** argv, const std::string& prog)
{
	// TCLAP keeps the pointer (and deletes its own default output when it is
	// replaced), so the output lives as long as the program.
	static QuietFailureOutput quiet;
	quiet.error.clear();
	cmd.setOutput(&quiet);
	if (cmd.parse(argc, argv)) return -1;
	if (quiet.error.empty()) return 0;
	std::cerr << prog << ": error: " << quiet.error << " (see --help)\n";
	return 2;
}
}  // namespace gam
