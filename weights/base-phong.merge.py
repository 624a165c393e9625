import json, os, sys
out, parts = sys.argv[1], sys.argv[2:]
os.makedirs(out, exist_ok=True)
train, test, count = [], [], 0
base = None
for k, p in enumerate(parts):
    m = json.load(open(os.path.join(p, "manifest.json")))
    if base is None: base = m
    for key in ("res", "truth_res", "image", "views", "shader", "input_supersample", "supersample"):
        assert m[key] == base[key], (p, key)
    if k < len(parts) - 1:
        assert m["train"]["count"] % 256 == 0, (p, m["train"]["count"])
        assert m["test"]["count"] == 0
    for s in m["train"]["shards"]:
        n = "p%02d-%s" % (k, s); os.rename(os.path.join(p, s), os.path.join(out, n)); train.append(n)
    count += m["train"]["count"]
    if k == len(parts) - 1:
        for s in m["test"]["shards"]:
            n = "p%02d-%s" % (k, s); os.rename(os.path.join(p, s), os.path.join(out, n)); test.append(n)
        last = m
merged = dict(last)
merged["train"] = {"count": count, "shards": train}
merged["test"] = {"count": last["test"]["count"], "shards": test}
merged["seed"] = last["seed"]
json.dump(merged, open(os.path.join(out, "manifest.json"), "w"), indent=2)
print("merged", count, "train +", last["test"]["count"], "test samples from", len(parts), "parts")
