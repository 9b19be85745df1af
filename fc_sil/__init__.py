"""silbridge.fc_sil"""
