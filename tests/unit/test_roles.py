"""The key-vehicle roles have one home, hcomc.road.KEY_ROLES, which every layer re-uses."""

from __future__ import annotations

import re
from pathlib import Path

from hcomc.control.prediction import population as rollout
from hcomc.interface import MergeGroup
from hcomc.metrics import KEY_ROLES as METRIC_ROLES
from hcomc.road import KEY_ROLES

SRC = Path(__file__).resolve().parents[2] / "src" / "hcomc"


def test_roles_are_the_six_key_vehicles_of_paper_fig_1() -> None:
    assert KEY_ROLES == ("VR", "VMC", "VMF", "VMR", "VNF", "VNR")
    assert METRIC_ROLES is KEY_ROLES
    assert len(KEY_ROLES) == rollout.N_ROLES
    roles = [rollout.VR, rollout.VMC, rollout.VMF, rollout.VMR, rollout.VNF, rollout.VNR]
    assert roles == list(range(len(KEY_ROLES)))


def test_merge_group_dict_follows_role_order() -> None:
    group = MergeGroup(vr=7, vmc=3, vmf=1, vmr=4, vnf=-1, vnr=9)
    assert list(group.as_dict()) == list(KEY_ROLES)
    assert list(group.as_dict().values()) == group.as_array().tolist()


def test_role_tuple_is_spelled_out_once_in_src() -> None:
    literal = re.compile(r'\(\s*"VR",\s*"VMC",\s*"VMF",\s*"VMR",\s*"VNF",\s*"VNR",?\s*\)')
    homes = [
        path.relative_to(SRC).as_posix()
        for path in sorted(SRC.rglob("*.py"))
        for _ in literal.finditer(path.read_text(encoding="utf-8"))
    ]
    assert homes == ["road.py"]
