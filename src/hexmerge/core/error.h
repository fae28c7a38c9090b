#pragma once
/// @file
/// The project's exception types and its always-on assertion.
///
/// Bad input (a user's mesh or parameters) throws InputError, which names the element or node at
/// fault. A broken internal invariant is a programmer error: HEXMERGE_ASSERT aborts the run with
/// an InternalError carrying the file, line and message.

#include <stdexcept>
#include <string>

#include "hexmerge/core/index.h"

namespace hexmerge {

/// What kind of entity an InputError points at.
enum class Entity { None, Node, Element, Parameter };

/// A user's input cannot be processed. `what()` is a complete sentence for the user.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& message, Entity entity = Entity::None, index_t id = NO_INDEX)
      : std::runtime_error(message), entity_(entity), id_(id) {}
  /// The kind of entity at fault (Entity::None when the whole input is at fault).
  Entity entity() const { return entity_; }
  /// 0-based index of the node or element at fault, NO_INDEX when none.
  index_t id() const { return id_; }

 private:
  Entity entity_;
  index_t id_;
};

/// The user cancelled a run through the progress callback.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("cancelled by the user") {}
};

/// The machine cannot give the run what it needs (threads, memory). `what()` is a complete
/// sentence for the user naming what ran out and, where one helps, the parameter to change.
class ResourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A broken internal invariant: a bug in HexMerge, never the user's fault.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

[[noreturn]] void assertion_failed(const char* condition, const char* message, const char* file,
                                   int line);

}  // namespace hexmerge

/// Always-on assertion for internal invariants (geogram's geo_assert).
#define HEXMERGE_ASSERT(condition, message)                                    \
  do {                                                                         \
    if (!(condition)) {                                                        \
      ::hexmerge::assertion_failed(#condition, (message), __FILE__, __LINE__); \
    }                                                                          \
  } while (false)
