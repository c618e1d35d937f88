#include "contact/contact_force.hpp"

#include <nlohmann/json.hpp>

namespace crackle::contact {

nlohmann::json contact_json(const PenaltyContact& contact) {
  const PenaltyChoice& penalty = contact.penalty();
  nlohmann::json json;
  json["penalty"] = penalty.normal_penalty;
  json["penalty_tangential"] = penalty.tangential_penalty;
  json["penalty_auto"] = penalty.automatic;
  if (penalty.automatic) {
    json["penalty_factor"] = penalty.factor;
    json["penalty_modulus"] = penalty.modulus;
    json["penalty_element_size"] = penalty.element_size;
  }
  json["friction"] = contact.options().friction_coefficient;
  json["contact_integration"] = contact.implicit() ? "implicit" : "explicit";
  return json;
}

}  // namespace crackle::contact
