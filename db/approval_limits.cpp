#include "db/approval_limits.hpp"

#include <nlohmann/json.hpp>

namespace calbench::db {

void publish_approval_limits(Store& store, const std::string& model, const Thresholds& t, const std::string& source) {
  if (!store.authenticated()) return;
  {  // only the owner writes them; `db init` by another login leaves them as they are
    auto own = store.connection().prepare("SELECT has_table_privilege('approval_limits', 'INSERT')");
    own.step();
    if (own.int64(0) == 0) return;
  }
  const auto triad = [](const TriadLimits& L) {
    return nlohmann::json{{"bias", L.max_abs_bias}, {"scale", L.max_abs_scale}, {"skew", L.max_abs_skew}};
  };
  const std::string limits = nlohmann::json{{"gyro", triad(t.gyro)}, {"accel", triad(t.accel)}}.dump();
  store.connection().write_transaction([&] {
    auto st = store.connection().prepare(
        "INSERT INTO approval_limits(model, limits, source) VALUES (?, CAST(? AS jsonb), ?) ON CONFLICT (model) DO UPDATE "
        "SET limits = excluded.limits, source = excluded.source, set_at = now(), set_by = session_user");
    st.bind(1, model).bind(2, limits).bind(3, source).run();
  });
}

}  // namespace calbench::db
