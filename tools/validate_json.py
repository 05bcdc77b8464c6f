#!/usr/bin/python3
"""Validates JSON documents (a file, or each line of a JSON-lines file) against a schema.

usage: validate_json.py SCHEMA INSTANCE [--lines]
Exit 0 when every document is valid; otherwise prints each error and exits 1.
"""
import json
import pathlib
import sys
import warnings

import jsonschema


def main() -> int:
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        schema = json.load(f)
    validator_class = jsonschema.validators.validator_for(schema)
    validator_class.check_schema(schema)
    # Schemas refer to their siblings by $id ("index-manifest.schema.json").
    store = {}
    for sibling in pathlib.Path(sys.argv[1]).resolve().parent.glob("*.schema.json"):
        with open(sibling) as f:
            document = json.load(f)
        store[document.get("$id", sibling.name)] = document
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        resolver = jsonschema.RefResolver(base_uri=schema.get("$id", ""), referrer=schema, store=store)
        validator = validator_class(schema, resolver=resolver)
    with open(sys.argv[2]) as f:
        text = f.read()
    documents = [json.loads(line) for line in text.splitlines() if line.strip()] if "--lines" in sys.argv else [json.loads(text)]
    errors = 0
    for number, document in enumerate(documents, 1):
        for error in validator.iter_errors(document):
            path = "/".join(str(p) for p in error.absolute_path)
            print(f"document {number}: /{path}: {error.message}")
            errors += 1
    if errors == 0:
        print(f"{len(documents)} document(s) valid")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
