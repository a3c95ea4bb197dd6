"""Deploying trained policies outside Python training code (ONNX export)."""

from retarget.deploy.onnx_export import (
    ExportedPolicy,
    export_onnx,
    export_post_stages,
    export_stage,
    policy_of,
)

__all__ = ["ExportedPolicy", "export_onnx", "export_post_stages", "export_stage", "policy_of"]
