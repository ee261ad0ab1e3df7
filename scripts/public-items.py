#!/usr/bin/env python3
"""Counts the public API of the `obscura` library crate.

Method: rustdoc's JSON output (nightly), walked from the crate root. An item counts
when a user can name it: modules, structs, enums, unions, traits, functions,
constants, statics, type aliases and macros reachable through public modules or
public re-exports (each item once, however many paths reach it), plus their public
members: fields of structs, variants of enums, and the items of inherent impls and
of traits (methods, associated constants and types). Trait implementations (Debug,
Clone, ...) and items only visible with `#[doc(hidden)]` are not counted.

    CARGO_TARGET_DIR=target/nightly-doc cargo +nightly rustdoc -p obscura --lib \
        -- -Z unstable-options --output-format json
    scripts/public-items.py target/nightly-doc/doc/obscura.json [--include-hidden]

rustdoc leaves `#[doc(hidden)]` items out of its JSON; to count them too (they stay
reachable by path), generate it with `--document-hidden-items` added after
`--output-format json` and pass `--include-hidden`.
"""
import collections
import json
import sys

args = [a for a in sys.argv[1:] if not a.startswith("--")]
include_hidden = "--include-hidden" in sys.argv
doc = json.load(open(args[0] if args else "target/nightly-doc/doc/obscura.json"))
index = doc["index"]
seen = set()
counts = collections.Counter()
by_module = collections.Counter()


def public(item):
    return item["visibility"] in ("public", "default")


def hidden(item):
    if include_hidden:
        return False
    return any("hidden" in str(a) for a in item.get("attrs", []))


def visit(item_id, module):
    item = index.get(str(item_id))
    if item is None or item["crate_id"] != 0 or item_id in seen:
        return
    if not public(item) or hidden(item):
        return
    kind, inner = next(iter(item["inner"].items()))
    if kind == "use":
        target = inner.get("id")
        if target is not None:
            if inner.get("is_glob"):
                t = index.get(str(target))
                if t and "module" in t["inner"]:
                    for child in t["inner"]["module"]["items"]:
                        visit(child, module)
            else:
                visit(target, module)
        return
    seen.add(item_id)
    counts[kind] += 1
    by_module[module] += 1
    if kind == "module":
        name = item["name"] if module == "" else module + "::" + item["name"]
        if item_id == doc["root"]:
            name = ""
        for child in inner["items"]:
            visit(child, name)
    elif kind == "struct":
        k = inner["kind"]
        fields = k.get("plain", {}).get("fields", []) if isinstance(k, dict) else []
        if isinstance(k, dict) and "tuple" in k:
            fields = [f for f in k["tuple"] if f is not None]
        for f in fields:
            visit(f, module)
        for i in inner["impls"]:
            visit_impl(i, module)
    elif kind == "enum":
        for v in inner["variants"]:
            visit(v, module)
        for i in inner["impls"]:
            visit_impl(i, module)
    elif kind == "union":
        for f in inner["fields"]:
            visit(f, module)
        for i in inner["impls"]:
            visit_impl(i, module)
    elif kind == "trait":
        for t in inner["items"]:
            visit(t, module)
    elif kind == "variant":
        k = inner["kind"]
        if isinstance(k, dict) and "struct" in k:
            for f in k["struct"]["fields"]:
                visit(f, module)


def visit_impl(impl_id, module):
    impl = index.get(str(impl_id))
    if impl is None:
        return
    inner = impl["inner"]["impl"]
    if inner["trait"] is not None or inner.get("is_synthetic") or inner.get("blanket_impl"):
        return
    for i in inner["items"]:
        visit(i, module)


visit(doc["root"], "")
total = sum(counts.values())
print(f"public items: {total}")
for k, n in counts.most_common():
    print(f"  {k:12} {n}")
print("by module (top level):")
top = collections.Counter()
for m, n in by_module.items():
    top[m.split("::")[0] or "(root)"] += n
for m, n in top.most_common():
    print(f"  {m:12} {n}")
