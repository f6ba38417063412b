// Typed attribute registry: named per-element columns added at run time
// (PMP's VertexProperty<T> style). Columns follow their table: they grow on
// allocation and are compacted with it. Look a property up once by name, then
// index the typed column in hot loops.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include <atelier/engine/handle.h>
#include <atelier/storage/slot_table.h>

namespace atelier {

namespace detail {
struct ColumnBase {
  virtual ~ColumnBase() = default;
  virtual void resize(std::size_t n) = 0;
  virtual void reset(std::size_t i) = 0;
  virtual void compact(const std::vector<std::uint32_t>& remap, std::size_t new_size) = 0;
  [[nodiscard]] virtual std::unique_ptr<ColumnBase> clone() const = 0;
  [[nodiscard]] virtual const std::type_info& type() const noexcept = 0;
  std::string name;
};

template <class T>
struct Column final : ColumnBase {
  std::vector<T> data;
  T fill{};
  void resize(std::size_t n) override { data.resize(n, fill); }
  void reset(std::size_t i) override { data[i] = fill; }
  void compact(const std::vector<std::uint32_t>& remap, std::size_t new_size) override {
    for (std::size_t i = 0; i < remap.size() && i < data.size(); ++i)
      if (remap[i] != Idx<void>::kInvalid && remap[i] != i) data[remap[i]] = std::move(data[i]);
    data.resize(new_size);
  }
  [[nodiscard]] std::unique_ptr<ColumnBase> clone() const override { return std::make_unique<Column>(*this); }
  [[nodiscard]] const std::type_info& type() const noexcept override { return typeid(T); }
};
}  // namespace detail

/// A typed reference to a registered column. Valid until the property is
/// removed; indexing by Idx<Tag> only, so a node property cannot be read
/// with a face index.
template <class Tag, class T>
class Property {
 public:
  Property() = default;
  explicit Property(detail::Column<T>* c) : col_(c) {}
  [[nodiscard]] bool valid() const noexcept { return col_ != nullptr; }
  T& operator[](Idx<Tag> i) { return col_->data[i.value]; }
  const T& operator[](Idx<Tag> i) const { return col_->data[i.value]; }
  [[nodiscard]] std::vector<T>& vector() { return col_->data; }
  [[nodiscard]] const std::vector<T>& vector() const { return col_->data; }

 private:
  detail::Column<T>* col_ = nullptr;
};

template <class Tag>
class PropertyRegistry {
 public:
  PropertyRegistry() = default;
  PropertyRegistry(const PropertyRegistry& o) : size_(o.size_) {
    for (const auto& c : o.cols_) cols_.push_back(c->clone());
  }
  PropertyRegistry& operator=(const PropertyRegistry& o) {
    if (this != &o) {
      PropertyRegistry t(o);
      *this = std::move(t);
    }
    return *this;
  }
  PropertyRegistry(PropertyRegistry&&) noexcept = default;
  PropertyRegistry& operator=(PropertyRegistry&&) noexcept = default;

  /// Adds a column; throws if the name exists with another type.
  template <class T>
  Property<Tag, T> add(std::string_view name, T fill = T{}) {
    if (auto p = find<T>(name); p.valid()) return p;
    if (find_any(name)) throw std::invalid_argument("property '" + std::string(name) + "' exists with another type");
    auto c = std::make_unique<detail::Column<T>>();
    c->name = std::string(name);
    c->fill = std::move(fill);
    c->resize(size_);
    auto* raw = c.get();
    cols_.push_back(std::move(c));
    return Property<Tag, T>(raw);
  }

  template <class T>
  [[nodiscard]] Property<Tag, T> find(std::string_view name) const {
    for (const auto& c : cols_)
      if (c->name == name && c->type() == typeid(T)) return Property<Tag, T>(static_cast<detail::Column<T>*>(c.get()));
    return {};
  }

  [[nodiscard]] bool contains(std::string_view name) const { return find_any(name) != nullptr; }

  bool remove(std::string_view name) {
    for (auto it = cols_.begin(); it != cols_.end(); ++it)
      if ((*it)->name == name) {
        cols_.erase(it);
        return true;
      }
    return false;
  }

  [[nodiscard]] std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& c : cols_) n.push_back(c->name);
    return n;
  }

  // Called by the owning table.
  void resize(std::size_t n) {
    size_ = n;
    for (auto& c : cols_) c->resize(n);
  }
  void reset(Idx<Tag> i) {
    for (auto& c : cols_) c->reset(i.value);
  }
  void compact(const std::vector<Idx<Tag>>& remap, std::size_t new_size) {
    std::vector<std::uint32_t> r(remap.size());
    for (std::size_t i = 0; i < remap.size(); ++i) r[i] = remap[i].value;
    for (auto& c : cols_) c->compact(r, new_size);
    size_ = new_size;
  }

 private:
  [[nodiscard]] const detail::ColumnBase* find_any(std::string_view name) const {
    for (const auto& c : cols_)
      if (c->name == name) return c.get();
    return nullptr;
  }
  std::vector<std::unique_ptr<detail::ColumnBase>> cols_;
  std::size_t size_ = 0;
};

}  // namespace atelier
