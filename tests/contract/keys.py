import json,sys
def walk(o,p,acc):
    if isinstance(o,dict):
        for k,v in o.items():
            acc.add(p+"."+k); walk(v,p+"."+k,acc)
    elif isinstance(o,list):
        for v in o: walk(v,p+"[]",acc)
acc=set(); text=sys.stdin.read()
try: docs=[json.loads(text)]
except ValueError: docs=[json.loads(l) for l in text.splitlines() if l.strip()]
for d in docs: walk(d,"",acc)
print("\n".join(sorted(acc)))
