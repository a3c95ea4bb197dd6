"""Deploying trained policies outside Python training code (ONNX export)."""

from retarget.deploy.onnx_export import ExportedPolicy, export_onnx, policy_of

__all__ = ["ExportedPolicy", "export_onnx", "policy_of"]
