#include "pipeline/command.h"

#include <utility>

namespace tolver {

const char* verdictName(Verdict v) {
  switch (v) {
    case Verdict::Ok:
      return "ok";
    case Verdict::NotMet:
      return "not met";
    case Verdict::Undecided:
      return "undecided";
    case Verdict::BadInput:
      return "bad input";
  }
  return "?";
}

int exitCode(Verdict v) {
  switch (v) {
    case Verdict::Ok:
      return 0;
    case Verdict::NotMet:
      return 1;
    case Verdict::BadInput:
      return 2;
    case Verdict::Undecided:
      return 4;
  }
  return 3;
}

Verdict worse(Verdict a, Verdict b) {
  auto rank = [](Verdict v) {
    switch (v) {
      case Verdict::Ok:
        return 0;
      case Verdict::Undecided:
        return 1;
      case Verdict::NotMet:
        return 2;
      case Verdict::BadInput:
        return 3;
    }
    return 3;
  };
  return rank(a) >= rank(b) ? a : b;
}

namespace {
InputNamer& namer() {
  static InputNamer n;
  return n;
}
}  // namespace

void setInputNamer(InputNamer n) { namer() = std::move(n); }

std::string inputName(const std::string& field) { return namer() ? namer()(field) : field; }

}  // namespace tolver
