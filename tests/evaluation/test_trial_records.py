"""Reading a results folder's per-trial records: sorted by file stem, for both benchmarks' folders; a malformed file
or a missing folder is a user error naming it."""

import json

import pytest

from slax_drake.errors import UserError
from slax_drake.evaluation.trial_records import analyse_trial_records, read_trial_records


def write_records(folder, kind, policy, records: dict) -> None:
    (folder / kind / policy).mkdir(parents=True)
    for stem, record in records.items():
        (folder / kind / policy / f"{stem}.json").write_text(json.dumps(record))


@pytest.mark.parametrize("kind", ["trials", "physics_trials"])
def test_records_are_read_by_file_stem_in_sorted_order(tmp_path, kind):
    records = {"10_0000": {"success": False}, "04_0001": {"success": True}, "04_0000": {"success": True}}
    write_records(tmp_path, kind, "dar", records)
    (tmp_path / kind / "dar" / ".04_0002.json.1234.tmp").write_text("{half")  # a file being written: not a record
    read = read_trial_records(tmp_path, "dar", kind=kind)
    assert list(read) == ["04_0000", "04_0001", "10_0000"]
    assert read == records


def test_each_kind_reads_its_own_folder(tmp_path):
    write_records(tmp_path, "trials", "dar", {"04_0000": {"simulator": "shelf"}})
    write_records(tmp_path, "physics_trials", "dar", {"04_0000": {"simulator": "drake"}})
    assert read_trial_records(tmp_path, "dar")["04_0000"] == {"simulator": "shelf"}
    assert read_trial_records(tmp_path, "dar", kind="physics_trials")["04_0000"] == {"simulator": "drake"}


@pytest.mark.parametrize("content,why", [("{not json", "not valid JSON"), (b"\xff\xfe\x00", "not valid JSON"),
                                         ("[1, 2]", "not a trial record"), ("null", "not a trial record")])
def test_a_malformed_file_is_a_user_error_naming_it(tmp_path, content, why):
    write_records(tmp_path, "trials", "dar", {"04_0000": {"success": True}})
    bad = tmp_path / "trials" / "dar" / "04_0001.json"
    if isinstance(content, bytes):
        bad.write_bytes(content)
    else:
        bad.write_text(content)
    with pytest.raises(UserError) as raised:
        read_trial_records(tmp_path, "dar")
    message = str(raised.value)
    assert message.startswith(f"{bad}: {why}") and "\n" not in message


def test_a_missing_policy_folder_is_a_user_error_or_no_records_when_allowed(tmp_path):
    with pytest.raises(UserError, match="no such folder") as raised:
        read_trial_records(tmp_path, "dar", kind="physics_trials")
    assert str(tmp_path / "physics_trials" / "dar") in str(raised.value)
    assert read_trial_records(tmp_path, "dar", missing_ok=True) == {}
    (tmp_path / "trials" / "dar").mkdir(parents=True)
    assert read_trial_records(tmp_path, "dar") == {}  # a folder without trial files yet


def test_an_unknown_kind_is_refused(tmp_path):
    with pytest.raises(ValueError, match="kind"):
        read_trial_records(tmp_path, "dar", kind="table1")


def test_analysing_records_names_a_record_that_lacks_what_the_analysis_reads(tmp_path):
    write_records(tmp_path, "physics_trials", "p", {"04_0000": {"drake": {"steps": 3}}, "04_0001": {"drake": {}}})
    with pytest.raises(UserError, match=r"a trial record lacks what a physics trial holds \(KeyError\('steps'\)\)"):
        analyse_trial_records(tmp_path, "p", lambda record: record["drake"]["steps"], kind="physics_trials")
    write_records(tmp_path, "trials", "p", {"04_0000": {"steps": 3}, "06_0000": {"steps": 5}})
    records, found = analyse_trial_records(tmp_path, "p", lambda record: record["steps"] * 2)
    assert list(records) == ["04_0000", "06_0000"] and found == {"04_0000": 6, "06_0000": 10}
    (tmp_path / "trials" / "q").mkdir()
    with pytest.raises(UserError, match="no trial files of q"):
        analyse_trial_records(tmp_path, "q", len)
