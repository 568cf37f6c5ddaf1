/* ShadyLoc command line: strict argument parsing (see CommandLine.h). */
#include "CommandLine.h"

#include <mrpt/3rdparty/tclap/StdOutput.h>

#include <charconv>
#include <cmath>
#include <iostream>

#include "shadyloc_commit.h"  // SHADYLOC_GIT_COMMIT, written at build time (cmake/WriteCommit.cmake)

#ifndef SHADYLOC_VERSION
#define SHADYLOC_VERSION "unknown"
#endif

namespace shadyloc::apps
{
const char* version() { return SHADYLOC_VERSION " (commit " SHADYLOC_GIT_COMMIT ")"; }

template <typename T>
T parseNumber(const std::string& text)
{
	const char* b = text.data();
	const char* e = b + text.size();
	// One leading '+' is fine ("+2"); from_chars takes no sign for it.
	if (b != e && *b == '+' && b + 1 != e && *(b + 1) != '-' && *(b + 1) != '+') b++;
	if (text.empty()) throw std::invalid_argument("empty value (a number is expected)");
	T v{};
	const auto r = std::from_chars(b, e, v);
	if (r.ec == std::errc::result_out_of_range)
		throw std::invalid_argument("'" + text + "' is out of range");
	if constexpr (std::is_floating_point_v<T>)
	{
		if (r.ec != std::errc() || r.ptr != e) throw std::invalid_argument("'" + text + "' is not a number");
		if (!std::isfinite(v)) throw std::invalid_argument("'" + text + "' is not a finite number");
	}
	else
	{
		if (r.ec != std::errc() || r.ptr != e)
		{
			// Say why: a fraction, a sign on an unsigned value, or no number at all.
			double d = 0;
			const auto rd = std::from_chars(b, e, d);
			if (rd.ec == std::errc() && rd.ptr == e && std::isfinite(d))
			{
				if (std::is_unsigned_v<T> && d < 0)
					throw std::invalid_argument("'" + text + "' is not a number >= 0");
				if (d != std::floor(d)) throw std::invalid_argument("'" + text + "' is not a whole number");
				throw std::invalid_argument("'" + text + "' is out of range");
			}
			throw std::invalid_argument("'" + text + "' is not a whole number");
		}
	}
	return v;
}

template int parseNumber<int>(const std::string&);
template unsigned parseNumber<unsigned>(const std::string&);
template long parseNumber<long>(const std::string&);
template unsigned long parseNumber<unsigned long>(const std::string&);
template double parseNumber<double>(const std::string&);

/** TCLAP output: usage and version to stdout (exit 0), failures recorded and
 * printed in the program's own error format. */
class CommandLine::Output : public TCLAP::StdOutput
{
   public:
	bool failed = false;
	void failure(TCLAP::CmdLineInterface& c, TCLAP::ArgException& e) override
	{
		failed = true;
		std::string arg = e.argId();
		if (arg.rfind("Argument: ", 0) == 0) arg = arg.substr(10);
		std::string why = e.error();
		if (why == "Couldn't find match for argument") why = "unknown option or extra argument";
		printError(c, (arg.empty() || arg == " " ? std::string() : arg + ": ") + why);
	}
	void printError(TCLAP::CmdLineInterface& c, const std::string& what)
	{
		std::cerr << c.getProgramName() << ": error: " << what << "\n";
		_shortUsage(c, std::cerr);
		std::cerr << "(" << c.getProgramName() << " --help for every option)\n";
	}
};

CommandLine::CommandLine(const std::string& description)
	: m_cmd(description, ' ', version()), m_output(std::make_unique<Output>())
{
	// TCLAP frees its own default output only if none was set: free it here.
	delete m_cmd.getOutput();
	m_cmd.setOutput(m_output.get());
}

CommandLine::~CommandLine() = default;

int CommandLine::usageError(const std::string& what)
{
	m_output->printError(m_cmd, what);
	return 2;
}

std::optional<int> CommandLine::parse(int argc, char** argv)
{
	if (!m_cmd.parse(argc, argv)) return m_output->failed ? 2 : 0;	// 0: --help, --version
	try
	{
		for (TCLAP::Arg* a : m_cmd.getArgList())
		{
			if (!a->isSet()) continue;
			const std::string name = a->getFlag().empty() && a->getName().empty() ? "" : a->getName();
			if (auto* v = dynamic_cast<TCLAP::ValueArg<std::string>*>(a))
			{
				const bool positional = dynamic_cast<TCLAP::UnlabeledValueArg<std::string>*>(a) != nullptr;
				const std::string& val = v->getValue();
				// A positional argument takes whatever comes; an unknown
				// option landing there is still an unknown option.
				if (positional && val.size() > 1 && val[0] == '-')
					throw std::invalid_argument(val + ": unknown option");
				if (val.empty() && !m_allowEmpty.count(a))
					throw std::invalid_argument(
						(positional ? "<" + name + ">" : "--" + name) + ": empty value");
			}
			else if (auto* m = dynamic_cast<TCLAP::MultiArg<std::string>*>(a))
			{
				for (const auto& val : m->getValue())
					if (val.empty()) throw std::invalid_argument("--" + name + ": empty value");
			}
		}
		for (NumberArgBase* n : m_numbers) n->validate();
	}
	catch (const std::invalid_argument& e)
	{
		return usageError(e.what());
	}
	return std::nullopt;
}

}  // namespace shadyloc::apps
