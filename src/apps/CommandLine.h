/* ShadyLoc command line: the one argument parser every subcommand uses.
 *
 * MRPT's bundled TCLAP returns false from parse() instead of exiting, for an
 * error and for --help alike, and its number parsing accepts "-1" for an
 * unsigned value. CommandLine wraps it so that:
 *   - a parse error prints "shadyloc <cmd>: error: <option>: <why>" and the
 *     short usage, and the command exits with 2 without running;
 *   - --help and --version print and exit with 0;
 *   - an unknown option is refused, also where a positional argument would
 *     have swallowed it;
 *   - an option given with an empty value is refused (unless allowEmpty());
 *   - numbers (NumberArg) are parsed strictly: the whole text, no NaN or
 *     infinity, no overflow, no fraction for whole numbers, a range checked.
 *
 * Usage:
 *   apps::CommandLine cli("What the command does.");
 *   TCLAP::ValueArg<std::string> in("i", "input", "input rawlog", true, "", "in.rawlog", cli.cmd());
 *   apps::NumberArg<double> alpha(cli, "", "alpha", "weight of log(blue)", 0.48, "a", 0.0, 1.0);
 *   if (const auto rc = cli.parse(argc, argv)) return *rc;
 */
#pragma once

#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <limits>
#include <sstream>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

namespace shadyloc::apps
{
/** The program's version, for --version. */
const char* version();

/** Strict text -> number. Throws std::invalid_argument with a message
 * ("'abc' is not a number", "'nan' is not a finite number", "'1e999' is out
 * of range", "'2.5' is not a whole number", "'-1' is not a number >= 0"). */
template <typename T>
T parseNumber(const std::string& text);

class CommandLine;

/** Type-erased part of NumberArg, checked by CommandLine::parse(). */
class NumberArgBase
{
   public:
	virtual ~NumberArgBase() = default;
	/** Parses and range-checks the value if given; throws std::invalid_argument. */
	virtual void validate() = 0;
	virtual std::string flag() const = 0;
};

/** A numeric option parsed strictly, with an inclusive range [lo, hi]. */
template <typename T>
class NumberArg : public NumberArgBase
{
	static_assert(std::is_arithmetic_v<T>);

   public:
	NumberArg(
		CommandLine& cli, const std::string& flag, const std::string& name, const std::string& desc, T def,
		const std::string& typeDesc, T lo = std::numeric_limits<T>::lowest(), T hi = std::numeric_limits<T>::max(),
		bool required = false);

	T getValue() const { return m_value; }
	bool isSet() const { return m_arg.isSet(); }
	void validate() override;
	std::string flag() const override { return "--" + m_arg.getName(); }

   private:
	TCLAP::ValueArg<std::string> m_arg;
	T m_value, m_lo, m_hi;
};

class CommandLine
{
   public:
	explicit CommandLine(const std::string& description);
	~CommandLine();
	CommandLine(const CommandLine&) = delete;
	CommandLine& operator=(const CommandLine&) = delete;

	TCLAP::CmdLine& cmd() { return m_cmd; }

	/** An option whose empty value means something ("" is refused otherwise). */
	void allowEmpty(const TCLAP::Arg& a) { m_allowEmpty.insert(&a); }

	/** Parses. Returns the exit code to return at once (0 after --help or
	 * --version, 2 after an error, already printed), or nullopt to run. */
	std::optional<int> parse(int argc, char** argv);

	/** Prints "<program>: error: <what>" and the short usage to stderr; returns 2. */
	int usageError(const std::string& what);

	void addNumber(NumberArgBase* n) { m_numbers.push_back(n); }

   private:
	class Output;
	TCLAP::CmdLine m_cmd;
	std::unique_ptr<Output> m_output;
	std::vector<NumberArgBase*> m_numbers;
	std::set<const TCLAP::Arg*> m_allowEmpty;
};

template <typename T>
NumberArg<T>::NumberArg(
	CommandLine& cli, const std::string& flag, const std::string& name, const std::string& desc, T def,
	const std::string& typeDesc, T lo, T hi, bool required)
	: m_arg(flag, name, desc, required, "", typeDesc, cli.cmd()), m_value(def), m_lo(lo), m_hi(hi)
{
	cli.addNumber(this);
}

template <typename T>
void NumberArg<T>::validate()
{
	if (!m_arg.isSet()) return;
	const std::string& text = m_arg.getValue();
	try
	{
		m_value = parseNumber<T>(text);
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument(flag() + ": " + e.what());
	}
	if (m_value < m_lo || m_value > m_hi)
	{
		auto str = [](T v) {
			if constexpr (std::is_floating_point_v<T>)
			{
				std::ostringstream s;
				s << v;
				return s.str();
			}
			else
				return std::to_string(v);
		};
		std::string range;
		if (m_lo == std::numeric_limits<T>::lowest()) range = "<= " + str(m_hi);
		else if (m_hi == std::numeric_limits<T>::max()) range = ">= " + str(m_lo);
		else range = "in [" + str(m_lo) + ", " + str(m_hi) + "]";
		throw std::invalid_argument(flag() + ": " + text + " is out of range (must be " + range + ")");
	}
}

}  // namespace shadyloc::apps
