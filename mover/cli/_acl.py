"""The access-control list of a team's router: who may serve which keys.

Written by ``mover router --gen-config`` into ``router.json`` (zenoh's ``access_control``).
Certificates name their holders (common name = member name); the team key still signs every
envelope on top, so the ACL is the second fence: it keeps a leaked certificate from serving
another member's keys (a hijacked queryable hears that member's calls), and keeps everything
but certificates of the team out of ``mover/<team>/**``. docs/security.md says what a leaked
certificate can and cannot do.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["team_acl"]


def team_acl(team: str, members: Sequence[str], tools: Sequence[str]) -> dict[str, Any]:
    """The router's access-control list for ``team`` (zenoh's ``access_control``).

    Default deny. Every certificate of the team may query, subscribe to and put on team topics
    (``bc/**``), put on control keys (``ctl/*``), follow liveliness, and is sent the team's
    topics, replies and declarations. Only ``<name>``'s certificate may serve ``<name>``'s
    keys: declare the queryables of ``rpc/<name>`` and ``hello/<name>`` and reply on them,
    subscribe to ``ctl/<name>``, hold the liveliness token ``alive/<name>``; and only it is
    sent the queries on ``rpc/<name>`` and ``hello/<name>`` and the puts on ``ctl/<name>``, so
    that a wildcard queryable or subscriber (``mover/<team>/**``) hears no other member's calls
    (zenoh admits a wildcard declaration that overlaps a rule: measured). A certificate of
    ``tools`` may serve any name but the members' (its processes take fresh names:
    ``run-1a2b3c``). A deny wins over an allow.
    """
    root = f"mover/{team}"

    def keys(name: str) -> dict[str, list[str]]:
        return {
            "serve": [f"{root}/rpc/{name}", f"{root}/hello/{name}"],
            "listen": [f"{root}/ctl/{name}"],
            "token": [f"{root}/alive/{name}"],
        }

    def rules(rid: str, k: dict[str, list[str]], permission: str = "allow") -> list[dict[str, Any]]:
        return [
            _rule(f"{rid}-serve", _SERVE, "ingress", k["serve"], permission),
            _rule(f"{rid}-listen", ["declare_subscriber"], "ingress", k["listen"], permission),
            _rule(f"{rid}-token", ["liveliness_token"], "ingress", k["token"], permission),
            _rule(f"{rid}-called", ["query"], "egress", k["serve"], permission),
            _rule(f"{rid}-told", ["put", "delete"], "egress", k["listen"], permission),
        ]

    topics, served = [f"{root}/bc/**"], [f"{root}/rpc/*", f"{root}/hello/*"]
    everyone = [
        _rule("team-query", ["query"], "ingress", served),
        _rule("team-put", ["put", "delete"], "ingress", [*topics, f"{root}/ctl/*"]),
        _rule("team-subscribe", ["declare_subscriber"], "ingress", topics),
        _rule("team-alive", _FOLLOW, "ingress", [f"{root}/alive/*"]),
        _rule("team-topics", ["put", "delete"], "egress", topics),
        _rule("team-replies", ["reply"], "egress", served),
        _rule("team-declared", [*_FOLLOW, *_DECLARE], "egress", [f"{root}/**"]),
    ]
    found = list(everyone)
    subjects: list[dict[str, Any]] = []
    policies: list[dict[str, Any]] = []
    common = [r["id"] for r in everyone]

    def policy(pid: str, names: list[str], own: list[dict[str, Any]]) -> None:
        found.extend(own)
        subjects.append({"id": pid, "cert_common_names": names})
        policies.append({"id": pid, "rules": common + [r["id"] for r in own], "subjects": [pid]})

    for i, name in enumerate(members):
        policy(f"m{i}", [name], rules(f"m{i}", keys(name)))
    if tools:
        theirs = {part: [k for n in members for k in keys(n)[part]] for part in keys("")}
        deny = rules("tools-not", theirs, "deny") if members else []
        policy("tools", list(tools), rules("tools", keys("*")) + deny)
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": found,
        "subjects": subjects,
        "policies": policies,
    }


_SERVE = ["declare_queryable", "reply"]
_FOLLOW = ["declare_liveliness_subscriber", "liveliness_query"]
_DECLARE = ["declare_subscriber", "declare_queryable", "liveliness_token"]


def _rule(
    rid: str, messages: list[str], flow: str, key_exprs: list[str], permission: str = "allow"
) -> dict[str, Any]:
    return {
        "id": rid,
        "messages": messages,
        "flows": [flow],
        "permission": permission,
        "key_exprs": key_exprs,
    }
