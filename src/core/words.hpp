#pragma once
/// \file A choice's words, each bound to the enum value it stands for: the one place a choice is
/// spelled. The scene's table declares the choice from it (`scene::choice(name, doc, words)`),
/// scene/ converts the validated word (`Values::choice`), outputs and messages name the value back
/// (`text_of`), and a command-line option checks against the same words (`texts_of`).
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"

namespace crackle {

/// One word of a choice and the value it stands for.
template <class E>
struct Word {
  const char* text;
  E value;
};

/// The words of a choice, in the order the scene's reference lists them.
template <class E, std::size_t N>
using Words = std::array<Word<E>, N>;

/// The words, in order: a scene table's choices, a command-line option's accepted values.
template <class E, std::size_t N>
std::vector<std::string> texts_of(const Words<E, N>& words) {
  std::vector<std::string> texts;
  for (const Word<E>& word : words) texts.emplace_back(word.text);
  return texts;
}

/// The word for `value` ("?" for a value without a word, which a table that lists every value of
/// its enum never meets).
template <class E, std::size_t N>
const char* text_of(const Words<E, N>& words, E value) {
  for (const Word<E>& word : words) {
    if (word.value == value) return word.text;
  }
  return "?";
}

/// The value `text` stands for; empty when it is none of the words.
template <class E, std::size_t N>
std::optional<E> value_of(const Words<E, N>& words, std::string_view text) {
  for (const Word<E>& word : words) {
    if (text == word.text) return word.value;
  }
  return std::nullopt;
}

/// The value `text` stands for; InputError `key: expected one of a, b, got 'text'` otherwise.
template <class E, std::size_t N>
E parse_word(const Words<E, N>& words, const std::string& text, const std::string& key) {
  if (const std::optional<E> value = value_of(words, text)) return *value;
  std::string accepted;
  for (const Word<E>& word : words) accepted += (accepted.empty() ? "" : ", ") + std::string(word.text);
  throw InputError(key + ": expected one of " + accepted + ", got '" + text + "'");
}

}  // namespace crackle
